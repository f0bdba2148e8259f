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

// The same with the first stage's accelerations `qdd_start` (dof) given: what
// ForwardDynamics would give at (q, qd) under tau (friction as `friction` says), known
// to the caller already (e.g. from a solve with M); saves one evaluation.
void Rk4StepFrom(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                 const Eigen::VectorXd& qdd_start, ArmStepWorkspace* work, Eigen::VectorXd* q, Eigen::VectorXd* qd);

// One semi-implicit Euler step of h seconds (friction included where `friction`).
void SemiImplicitEulerStep(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                           ArmStepWorkspace* work, Eigen::VectorXd* q, Eigen::VectorXd* qd);

// A rigid arm with its joint_flexibility motors (arm_effects.h): the links' state and the
// motors' (dof each; a rigid joint's motor entries are unused).
struct FlexibleArmState {
  Eigen::VectorXd q, qd;              // dof, rad or m: the links
  Eigen::VectorXd motor_q, motor_qd;  // dof, rad or m: the flexible joints' motors
};

// One RK4 step of h seconds of the coupled equations of the links and the motors under
// the drive torques `drive` (dof, held over the step), the spring of every stage
// evaluated at that stage: J_m thm'' = u - tau_s with tau_s = k (thm - q) + d (thm' - qd)
// on a flexible joint, whose link gets tau_s; a rigid joint's link gets u. Friction off.
// The fine-step reference the Newtonian backend's flexible joints are measured against
// (it allocates; it is not the backend's step). Throws std::invalid_argument for wrong
// sizes.
void FlexibleRk4Step(const ArmModel& plant, const Eigen::VectorXd& drive, double h, FlexibleArmState* x);

}  // namespace twinsim
