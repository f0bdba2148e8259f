// One time step of a rigid arm's equations of motion (q, qd)' = (qd, qdd), qdd from
// ForwardDynamics (arm_dynamics.h) under a torque held over the step:
//   Rk4Step               the classical fourth-order Runge-Kutta method, four
//                         evaluations of the dynamics; the analytic backend's step;
//   SemiImplicitEulerStep qd += h qdd(q, qd), then q += h qd (symplectic Euler, one
//                         evaluation; MuJoCo's mjINT_EULER without damping).
// An ArmStepWorkspace holds the stages, so that stepping allocates nothing once it has
// been used with the model's dof().
//
//   ArmStepWorkspace w;
//   for (...) Rk4Step(plant, tau, 1e-3, /*friction=*/false, &w, &q, &qd);
#pragma once

#include <Eigen/Core>

#include "robots/arm/arm_model.h"

namespace twinsim {

// Scratch for the steps below; its content between calls means nothing.
struct ArmStepWorkspace {
  Eigen::VectorXd q;                  // a stage's positions
  Eigen::VectorXd qd2, qd3, qd4;      // the stages' velocities
  Eigen::VectorXd qdd1, qdd2, qdd3, qdd4;  // the stages' accelerations
};

// One RK4 step of h seconds (friction included where `friction`).
void Rk4Step(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction, ArmStepWorkspace* work,
             Eigen::VectorXd* q, Eigen::VectorXd* qd);

// One semi-implicit Euler step of h seconds (friction included where `friction`).
void SemiImplicitEulerStep(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                           ArmStepWorkspace* work, Eigen::VectorXd* q, Eigen::VectorXd* qd);

}  // namespace twinsim
