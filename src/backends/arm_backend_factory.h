// Builds any arm backend by name: the Newtonian backend over one of the engines
// ("analytic", "ode", "bullet"; engines/arm_engine.h) with the arm's friction and
// effects, or the learned one ("learned", with a 1-sample predictor trained for the
// model). The one place that knows every arm backend; its twin for the omni robot is
// backends/omni_backend_factory.h.
//
//   ArmSimulation sim(model, MakeArmBackend("bullet", model));
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"
#include "sim/arm_backend.h"

namespace twinsim {

class ArmPredictor;

struct ArmBackendOptions {
  // Physics steps per sample of the Newtonian backends (sim/newtonian_arm_backend.h);
  // 0 = automatic. The learned backend steps whole samples: 0 or 1 only.
  int physics_substeps = 0;
  // s: the engine's longest internal integration step (ArmEngineOptions::max_step);
  // 0 = the engine's default.
  double max_step = 0;
  std::shared_ptr<const ArmPredictor> predictor;  // the learned backend's 1-sample predictor

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// Builds the backend called `name` (analytic, ode, bullet, learned) for `model` (the
// Newtonian ones over ArmPlantModel(model): its payload lumped into the last link), at
// q = 0 and at rest. Throws InputError for an unknown or uncompiled backend, bad
// options, a learned one without a fitting predictor, or a model that does not
// Validate().
std::unique_ptr<ArmBackend> MakeArmBackend(const std::string& name, const ArmModel& model,
                                           const ArmBackendOptions& options = {});

// The backend names a user may pass to --backend for an arm in this build.
std::vector<std::string> AvailableArmBackends();

}  // namespace twinsim
