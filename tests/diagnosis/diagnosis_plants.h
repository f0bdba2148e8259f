// Plants with hidden effects for the diagnosis tests: logs recorded from a model with
// effects switched on, with realistic sensor noise, handed to the diagnosis with the
// nominal model only (the code under test is never told what was hidden).
#pragma once

#include <cstdint>
#include <string>

#include "diagnosis/diagnosis.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {
namespace testing {

// Records what `report` named and its held-out gaps beside the plant's own (`floor`) as
// properties of the running test (--gtest_output=xml), from which docs/diagnose.md's
// counts and confusion table are made.
void RecordDiagnosis(const DiagnosisReport& report, double floor);

struct ArmRecording {
  double counts_per_rev = 2e5;  // encoder counts per joint revolution (q quantised); 0: exact
  double torque_noise = 0.02;   // N·m, standard deviation on the logged command
  bool log_velocities = false;  // false: the log holds q and tau only, qd and qdd are derived
  double cutoff_hz = 10;        // Hz, the reader's cut-off for derived qd, qdd
  double bandwidth = 10;        // Hz, the computed-torque controller's
};

// A stop-and-go (even seeds) or multi-sine (odd seeds) tracking run of `plant` under
// computed torque over `hat` with a torque dither, as a real arm's controller logs it.
ArmLog RecordArmPlant(const ArmModel& plant, const ArmModel& hat, std::uint64_t seed, double seconds,
                      const ArmRecording& noise = {});

// The RRR arm of seed 001 (models/rrr.yaml) with `effects` (YAML list items, e.g.
// "{name: viscous_friction, joint: 2, b: 0.5}") added.
ArmModel RrrWith(const std::string& effects_yaml);

// A random drive of `plant` (camera noise as the shipped models: 1 mm, 0.005 rad) of
// `seconds` at 30 fps on the analytic backend.
OmniLog RecordOmniPlant(const OmniModel& plant, double seconds, std::uint64_t seed);

}  // namespace testing
}  // namespace twinsim
