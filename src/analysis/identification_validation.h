// Judging an identified arm model on held-out logs (`twinsim identify --validate`): the
// torque errors on logs the identification never saw, of the a-priori model, of the
// identified (physically consistent) model, and of the unconstrained least-squares
// estimate, which predicts straight from its base parameters; and the motion the
// a-priori and the identified model simulate from the logs' torques. The first and the last
// edge_samples rows of each log are left out, where derived velocities and
// accelerations are least reliable.
//
//   IdentificationValidation v = ValidateIdentification(a_priori, identified, summary, options, held_out);
//   std::printf("%s", v.FullReport().c_str());
//   WriteFileAtomically("report/validation.csv", FormatIdentificationValidationCsv(v));
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "analysis/arm_replay.h"
#include "analysis/arm_simulation_score.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// The torque errors of the three models on one held-out log.
struct HeldOutTorqueErrors {
  std::string path;            // the log's file
  TorqueErrors a_priori;       // the a-priori model's commands
  TorqueErrors identified;     // the identified model's commands: its offsets, delays and kept effects included
  TorqueErrors unconstrained;  // Y_b beta of the unconstrained estimate, plus the estimated offsets
};

struct IdentificationValidation {
  std::vector<HeldOutTorqueErrors> logs;  // in the order given
  // Per log, the a-priori and the identified model simulated from the log's torques
  // ("a-priori", "identified"; analysis/arm_simulation_score.h), at the default horizons
  // that fit in the log.
  std::vector<std::pair<std::string, ArmSimulationScore>> simulated;

  // Per log: a table of the torque RMS and the three errors per joint (N·m or N, and
  // percent of the torque RMS), and the mean relative and normalised errors; then the
  // simulation errors; empty without logs.
  std::string FullReport() const;
};

// The errors on every log of `held_out` of `a_priori`, of `identified` and of the
// unconstrained estimate in `summary`, all from IdentifyArmByLeastSquares() with `options`. Throws
// InputError when a log's joint count differs from the models'.
IdentificationValidation ValidateIdentification(const ArmModel& a_priori, const ArmModel& identified,
                                                const WlsIdentificationSummary& summary,
                                                const WlsIdentificationOptions& options,
                                                const std::vector<ArmLog>& held_out);

// Adds `model`'s simulation scores on `held_out` to validation->simulated under `name`,
// each log's just before its "identified" entry.
void AddSimulatedModel(IdentificationValidation* validation, const std::string& name, const ArmModel& model,
                       const std::vector<ArmLog>& held_out);

// validation.csv: log,joint,torque_rms,error_a_priori,error_identified,error_unconstrained,
// relative_a_priori,relative_identified,relative_unconstrained, one row per log and joint
// (N·m or N; relative as fractions of the torque RMS).
std::string FormatIdentificationValidationCsv(const IdentificationValidation& validation);

}  // namespace twinsim
