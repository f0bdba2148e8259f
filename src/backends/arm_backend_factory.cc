#include "backends/arm_backend_factory.h"

#include "backends/learned/learned_arm_backend.h"
#include "core/error.h"
#include "sim/newtonian_arm_backend.h"

namespace twinsim {

bool ArmBackendOptions::IsValid(std::string* why) const {
  if (physics_substeps < 0 || physics_substeps > 100000) {
    if (why) *why = "physics_substeps must be in [0, 100000] (0 = automatic)";
    return false;
  }
  return ArmEngineOptions{max_step}.IsValid(why);
}

std::vector<std::string> AvailableArmBackends() {
  std::vector<std::string> names = AvailableArmEngines();
  names.push_back("learned");
  return names;
}

std::unique_ptr<ArmBackend> MakeArmBackend(const std::string& name, const ArmModel& model,
                                           const ArmBackendOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("arm backend options: " + why);
  if (name != "analytic" && name != "ode" && name != "bullet" && name != "learned") {
    throw InputError("unknown arm backend '" + name + "' (known: analytic, ode, bullet, learned)");
  }
  if (name == "learned") {
    // A learned model of the real arm has its friction and effects: it steps whole samples.
    if (options.physics_substeps > 1) {
      throw InputError("arm simulation options: the learned backend steps one whole sample at a time; "
                       "physics_substeps must be 0 or 1");
    }
    if (!options.predictor) throw InputError("the learned arm backend needs a predictor (twinsim train)");
    return MakeLearnedArmBackend(model, *options.predictor);
  }
  return MakeNewtonianArmBackend(name, model, options.physics_substeps, ArmEngineOptions{options.max_step});
}

}  // namespace twinsim
