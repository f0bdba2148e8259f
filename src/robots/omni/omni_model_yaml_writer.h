// Writing any OmniModel as a complete, standalone model file in the schema of
// docs/models.md (no `extends:`): every key the reader knows, and an `effects:` block
// with only the effects that are on. Programs that change a model (identification,
// `twinsim diagnose`) write their result with it, and it loads anywhere a model does
// (LoadOmniModel). Numbers are written in their shortest form that reads back as the
// same double, so loading the file gives back the same model bit for bit. Wheel angles
// are stored in rad and written in degrees: they read back exactly whenever they came
// from degrees (every loaded model), others to within one unit in the last place.
// `chassis.inertia_z` is the value given (0 = solid cylinder), not the derived one.
//
//   WriteOmniModelYaml("out/omni4_identified.yaml", model, "identified from run1.csv");
#pragma once

#include <string>

#include "robots/omni/omni_model.h"

namespace twinsim {

// The YAML text of `model`; `comment` (may be several lines) goes at the top as # lines.
std::string FormatOmniModelYaml(const OmniModel& model, const std::string& comment = "");

// Writes FormatOmniModelYaml() atomically. Throws InputError when the file cannot be written.
void WriteOmniModelYaml(const std::string& path, const OmniModel& model, const std::string& comment = "");

}  // namespace twinsim
