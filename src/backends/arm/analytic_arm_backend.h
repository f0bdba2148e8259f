// The "analytic" arm backend: the model's own rigid-body dynamics
// (ForwardDynamics in robots/arm/arm_dynamics.h, friction off) integrated by the
// classical fourth-order Runge-Kutta method, each Step cut into internal steps of at
// most ArmBackendOptions::max_step. Its state is (q, qd) and nothing else, so Save()
// and Restore() are exact. It is the reference the engines are measured against.
#pragma once

#include <memory>

#include "backends/arm/arm_backend.h"

namespace twinsim {

// Builds it for `plant` (already ArmPlantModel()); `options` must be valid.
std::unique_ptr<ArmBackend> MakeAnalyticArmBackend(const ArmModel& plant, const ArmBackendOptions& options);

// Internal steps for one Step of dt seconds with steps of at most max_step (>= 1).
int ArmSubsteps(double dt, double max_step);

// Throws std::invalid_argument unless q and qd have `dof` finite entries.
void CheckArmState(const std::string& backend, int dof, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
// Throws std::invalid_argument unless tau has `dof` entries and dt > 0 is finite.
void CheckArmStep(const std::string& backend, int dof, const Eigen::VectorXd& tau, double dt);

}  // namespace twinsim
