// Identification of an arm from its logs as `twinsim identify` runs it, in the shape of
// the omni robot's (identification_omni/omni_identification.h): the model into
// *identified, and a report of every step returned.
//
//   1. the base parameters and friction by weighted least squares on the torques
//      (IdentifyArmByLeastSquares, identification/wls_identification.h);
//   2. optionally refined on the simulation error, stage after stage, each from where the
//      last ended (RefineArmByOutputError, analysis/arm_output_error.h);
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
};

struct ArmIdentificationReport {
  WlsIdentificationSummary least_squares;
  ArmModel inverse_dynamics;                     // the least squares' model, before any refinement
  std::vector<ArmOutputErrorSummary> output_error;  // per stage
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
