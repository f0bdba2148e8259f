// Builds any omni backend by name: the Newtonian backend over one of the engines
// ("analytic", "ode", "bullet"; engines/omni_engine.h) or the learned one ("learned",
// with a 1-frame predictor). The one place that knows every omni backend; its twin for
// the arm is backends/arm_backend_factory.h. A field whose robots run on different
// backends gets one of each, behind a GroupedOmniBackend (sim/grouped_omni_backend.h).
//
//   std::unique_ptr<OmniBackend> b = MakeOmniBackend("ode", robots, field, timing);
//   std::unique_ptr<OmniBackend> m = MakeOmniBackend({{"ode"}, {"analytic"}}, robots, {"blue0", "yellow0"},
//                                                    field, timing);
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

// One robot's backend on a field whose robots may run on different ones.
struct RobotBackendChoice {
  std::string name;  // analytic, ode, bullet, learned
  std::shared_ptr<const OmniPredictor> predictor;  // learned: its 1-frame predictor; ignored by the others
};

// Builds a field whose robot i runs on per_robot[i]: the robots that name the same
// backend (and, learned, the same predictor object) share one backend, in the order of
// their first robot, each backend's robots in field order. When they all share one,
// that backend is returned as MakeOmniBackend(name, ...) builds it (no composite);
// otherwise a GroupedOmniBackend whose name() lists each backend with its robots'
// `labels`. Throws std::invalid_argument when the lists are not one per robot, and as
// MakeOmniBackend.
std::unique_ptr<OmniBackend> MakeOmniBackend(const std::vector<RobotBackendChoice>& per_robot,
                                             const std::vector<OmniModel>& robots,
                                             const std::vector<std::string>& labels, const FieldModel& field,
                                             const FrameTiming& timing);

// The backend names a user may pass to --backend in this build.
std::vector<std::string> AvailableOmniBackends();

}  // namespace twinsim
