#include "engines/arm_engine.h"
#include "engines/omni_engine.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/engine_names.h"
#include "core/error.h"
#include "engines/analytic/analytic_arm_engine.h"
#include "robots/arm/arm_effects.h"
#ifdef TWINSIM_HAVE_ODE
#include "engines/ode/ode_arm_engine.h"
#endif
#ifdef TWINSIM_HAVE_BULLET
#include "engines/bullet/bullet_arm_engine.h"
#endif

namespace twinsim {

bool ArmEngineOptions::IsValid(std::string* why) const {
  if (!(max_step >= 0) || !std::isfinite(max_step)) {
    if (why) *why = "max_step must be 0 (the backend's default) or a positive number of seconds";
    return false;
  }
  return true;
}

double DefaultArmMaxStep(const std::string& backend) {
  // Chosen from the measured agreement (docs/arm_backends.md): the analytic model's and
  // Bullet's RK4 are within 2e-7 rad of a 10 us reference after 2 s of free swing at
  // 1 ms; ODE's first-order steps need finer ones.
  if (backend == "analytic") return 1e-3;
  if (backend == "bullet") return 1e-3;
  if (backend == "ode") return 1.25e-4;
  return 1e-3;
}

int ArmSubsteps(double dt, double max_step) {
  return std::max(1, static_cast<int>(std::ceil(dt / max_step - 1e-9)));
}

void CheckArmState(const std::string& backend, int dof, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  if (q.size() != dof || qd.size() != dof) {
    throw std::invalid_argument(backend + " arm backend: " + std::to_string(q.size()) + " positions and " +
                                std::to_string(qd.size()) + " velocities for an arm with " + std::to_string(dof) +
                                " joints");
  }
  if (!q.allFinite() || !qd.allFinite()) throw std::invalid_argument(backend + " arm backend: non-finite state");
}

void CheckArmStep(const std::string& backend, int dof, const Eigen::VectorXd& tau, double dt) {
  if (tau.size() != dof) {
    throw std::invalid_argument(backend + " arm backend: " + std::to_string(tau.size()) +
                                " torques for an arm with " + std::to_string(dof) + " joints");
  }
  if (!(dt > 0) || !std::isfinite(dt)) {
    throw std::invalid_argument(backend + " arm backend: step " + std::to_string(dt) + " s must be > 0");
  }
}

// Every engine that is built simulates both robots: the lists are the same.
std::vector<std::string> AvailableArmEngines() { return AvailableOmniEngines(); }

std::unique_ptr<ArmEngine> MakeArmEngine(const std::string& name, const ArmModel& model,
                                           const ArmEngineOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("arm backend options: " + why);
  if (!IsKnownEngine(name)) {
    throw InputError("unknown arm backend '" + name + "' (known: analytic, ode, bullet)");
  }
  if (const std::string problems = model.Validate(); !problems.empty()) {
    throw InputError("arm model '" + model.name + "': " + problems);
  }
  const ArmModel plant = ArmPlantModel(model);
  if (name == "analytic") return MakeAnalyticArmEngine(plant, options);
  if (name == "ode") {
#ifdef TWINSIM_HAVE_ODE
    return MakeOdeArmEngine(plant, options);
#else
    throw InputError("ode backend not compiled; rebuild with -DTWINSIM_WITH_ODE=ON");
#endif
  }
#ifdef TWINSIM_HAVE_BULLET
  return MakeBulletArmEngine(plant, options);
#else
  throw InputError("bullet backend not compiled; rebuild with -DTWINSIM_WITH_BULLET=ON");
#endif
}

}  // namespace twinsim
