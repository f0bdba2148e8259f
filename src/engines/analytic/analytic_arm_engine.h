// The "analytic" arm backend: the model's own rigid-body dynamics
// (ForwardDynamics in robots/arm/arm_dynamics.h, the articulated-body algorithm,
// friction off) integrated by the classical fourth-order Runge-Kutta method
// (Rk4Step, robots/arm/arm_integrators.h), each Step cut into internal steps of at
// most ArmEngineOptions::max_step. Its state is (q, qd) and nothing else, so Save()
// and Restore() are exact. It is the reference the engines are measured against.
#pragma once

#include <memory>

#include "engines/arm_engine.h"

namespace twinsim {

// Builds it for `plant` (already ArmPlantModel()); `options` must be valid.
std::unique_ptr<ArmEngine> MakeAnalyticArmEngine(const ArmModel& plant, const ArmEngineOptions& options);

}  // namespace twinsim
