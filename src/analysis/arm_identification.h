// Identification of an arm from its logs as `twinsim identify` runs it, in the shape of
// the omni robot's (identification_omni/omni_identification.h): the model into
// *identified, and a report of every step returned.
//
//   1. the base parameters and friction by weighted least squares on the torques
//      (IdentifyArmByLeastSquares, identification/wls_identification.h);
//   2. optionally refined on the simulation error, stage after stage, each from where the
//      last ended (RefineArmByOutputError, analysis/arm_output_error.h); the first from
//      the least squares' model, or from the a-priori model where that simulates the
//      first stage's fit windows better (ArmOutputErrorStartCost): a torque fit can leave
//      inertias the data barely determines (a wrist's) further from the truth than a
//      data sheet, and the simulation error is not convex, so the start decides which
//      minimum the refinement finds;
//   3. with held-out logs, judged on them: the torque errors of the a-priori, the
//      identified and the unconstrained model, and the motion each simulates from the
//      logged torques (ValidateIdentification, analysis/identification_validation.h;
//      with output error the least squares' model too, as "inverse dynamics").
//
//   ArmIdentificationOptions options;
//   ArmModel identified;
//   ArmIdentificationReport report = IdentifyArm(a_priori, logs, held_out, options, &identified);
//   std::printf("%s", report.FullReport().c_str());
#pragma once

#include <string>
#include <vector>

#include "analysis/arm_output_error.h"
#include "analysis/identification_validation.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

struct ArmIdentificationOptions {
  WlsIdentificationOptions least_squares;
  // The output-error stages in turn, each refining the last one's model; none: the least
  // squares' model is the identified one.
  std::vector<ArmOutputErrorOptions> output_error;
  // The first stage may start from the a-priori model (its inertia, friction and
  // effects, with the least squares' torque offsets: a sensor's bias no data sheet
  // knows) where that simulates the stage's fit windows better than the least squares'
  // model; false: always from the least squares'.
  bool a_priori_start = true;
};

struct ArmIdentificationReport {
  WlsIdentificationSummary least_squares;
  ArmModel inverse_dynamics;                     // the least squares' model, before any refinement
  std::vector<ArmOutputErrorSummary> output_error;  // per stage
  // With output error: where the first stage started, and both candidates' start costs
  // (ArmOutputErrorStartCost; the a-priori's 0 when not tried).
  bool started_from_a_priori = false;
  double start_cost_least_squares = 0, start_cost_a_priori = 0;
  IdentificationValidation validation;           // on the held-out logs (empty without)
  double seconds = 0;                            // wall time

  // The least squares' tables, the torque offsets, each output-error stage's table and
  // the held-out logs' errors, as identify prints them.
  std::string FullReport() const;
};

// Identifies `a_priori` from `logs` and judges it on `held_out` (logs derived as the
// fitted ones were): the model into *identified (not null), the report returned. Throws
// InputError as the steps do (options, joint counts, data that does not excite a
// parameter, logs too short for the output error's windows).
ArmIdentificationReport IdentifyArm(const ArmModel& a_priori, const std::vector<ArmLog>& logs,
                                    const std::vector<ArmLog>& held_out, const ArmIdentificationOptions& options,
                                    ArmModel* identified);

}  // namespace twinsim
