// Builds any omni backend by name: the Newtonian backend over one of the engines
// ("analytic", "ode", "bullet"; engines/omni_engine.h) or the learned one ("learned",
// with a 1-frame predictor). The one place that knows every omni backend; its twin for
// the arm is backends/arm_backend_factory.h.
//
//   std::unique_ptr<OmniBackend> b = MakeOmniBackend("ode", robots, field, timing);
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engines/omni_engine.h"
#include "sim/omni_backend.h"

namespace twinsim {

class OmniPredictor;

// What some backends need besides the models.
struct OmniBackendOptions {
  std::shared_ptr<const OmniPredictor> predictor;  // the learned backend's 1-frame predictor
};

// Builds the backend called `name` (analytic, ode, bullet, learned). Throws InputError
// for an unknown or uncompiled backend, or a learned one without a fitting predictor.
std::unique_ptr<OmniBackend> MakeOmniBackend(const std::string& name, const std::vector<OmniModel>& robots,
                                             const FieldModel& field, const FrameTiming& timing,
                                             const OmniBackendOptions& options = {});

// The backend names a user may pass to --backend in this build.
std::vector<std::string> AvailableOmniBackends();

}  // namespace twinsim
