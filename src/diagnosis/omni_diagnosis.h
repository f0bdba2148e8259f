// Diagnosis of an omni robot model against measured omni logs (diagnosis.h,
// docs/diagnose.md).
//
// The residual is the contract's `replay`: each frame predicted from the measured state
// `horizon` frames earlier (4 by default) through the model and its delay, the measured
// pose minus the predicted one, per row as (forward, sideways) in the robot's frame and the heading
// error times the chassis radius (a point on the robot's rim), all in metres. The gap
// is the RMS of its length over held-out rows. Every candidate effect of the omni
// vocabulary is fitted on the replay itself: a grid first, then a golden-section search
// for one parameter or Ceres for several (and, for the time delay, whose effect moves in
// physics steps, a search step by step).
//
//   DiagnosisOptions options;           // options.backend: analytic (default), ode or bullet
//   OmniModel repaired;
//   DiagnosisReport report = DiagnoseOmni(model, logs, options, &repaired);
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// Diagnoses `model` on `logs`. *repaired (if given) receives the model with the effects
// added. Throws InputError for logs too short to hold a block out, non-finite values,
// an unknown backend or invalid options; CheckFailed when the model diverges.
DiagnosisReport DiagnoseOmni(const OmniModel& model, const std::vector<OmniLog>& logs, const DiagnosisOptions& options,
                             OmniModel* repaired = nullptr,
                             const std::function<void(const std::string&)>& progress = {});

}  // namespace twinsim
