// Writing any ArmModel as the project's YAML with a URDF-style joint table (each joint's
// origin xyz + rpy and axis in its parent link's frame; link inertials in the link frame
// about the centre of mass) and its effects (an `effects:` list with every effect that is
// on, joints by 1-based number), so that identified models load anywhere a model does
// (LoadArmModel). Numbers are written with 17 significant digits: loading the file gives
// back the same doubles, and the same rotation to within 1e-15 (rpy angles). The schema
// is in docs/arm_models.md.
//
//   WriteArmModelYaml("out/kuka_identified.yaml", model, "identified from run1.csv");
#pragma once

#include <string>

#include "robots/arm/arm_model.h"

namespace twinsim {

// The YAML text of `model`; `comment` (may be several lines) goes at the top as # lines.
std::string FormatArmModelYaml(const ArmModel& model, const std::string& comment = "");

// Writes FormatArmModelYaml() atomically. Throws InputError when the file cannot be written.
void WriteArmModelYaml(const std::string& path, const ArmModel& model, const std::string& comment = "");

}  // namespace twinsim
