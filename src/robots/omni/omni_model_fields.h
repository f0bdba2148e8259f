// The numbers of an omni model file outside `effects:` (those are omni_effects.h's
// OmniEffectField table): where each sits in the file, its unit, its valid range and
// where it lives in OmniModel. The model file's reader and writer (omni_model_yaml.cc,
// omni_model_yaml_writer.cc) and `identify` (identification_omni/omni_identification.cc)
// read these, so that a key, a unit or a range is written once (issue 66); `batch`'s
// sweeps set the same keys through the reader.
//
// The table holds the file's keys in the file's order, section by section. A key whose
// value is not one number (`chassis.com`, `wheels.angles_deg`, `motor.strength`,
// `driving_noise.simulated`) is listed for its place and unit and `custom`: the reader and
// the writer handle it at that place themselves.
//
//   const OmniModelField& f = OmniModelFieldAt("controller.forward.slew_rate");
//   f.set(&model, 3.0);  // m/s^2, f.unit
#pragma once

#include <string>
#include <vector>

#include "io/yaml_reader.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

struct OmniModelField {
  std::string section;  // "chassis", "controller.forward", "driving_noise.drift"
  std::string key;      // within its section: "mass"
  std::string unit;     // the writer's comment where it writes one; "" for none
  NumberCheck check;    // the reader's
  double (*get)(const OmniModel&) = nullptr;
  void (*set)(OmniModel*, double) = nullptr;
  bool integer = false;          // a whole number (read as one, written without a point)
  bool omitted_at_zero = false;  // the writer leaves it out where it is 0 (off)
  bool custom = false;           // not one number: read and written by the section's own code

  std::string path() const { return section + "." + key; }
};

// Every field, in the file's order.
const std::vector<OmniModelField>& OmniModelFields();

// The fields of one section, in the file's order.
std::vector<const OmniModelField*> OmniModelFieldsOf(const std::string& section);

// The field at `path` ("controller.forward.slew_rate"); throws std::logic_error for a
// path the table does not hold (a program's error, not a user's).
const OmniModelField& OmniModelFieldAt(const std::string& path);

}  // namespace twinsim
