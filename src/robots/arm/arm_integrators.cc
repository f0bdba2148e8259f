#include "robots/arm/arm_integrators.h"

#include <stdexcept>

#include "robots/arm/arm_dynamics.h"

namespace twinsim {

namespace {

// RK4's stages 2 to 4 and the update, from the first stage's accelerations in w->qdd1.
// Stage k's velocity is also the position derivative of stage k (k1q = qd).
void Rk4Stages(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction, ArmStepWorkspace* w,
               Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  w->qd2 = *qd + 0.5 * h * w->qdd1;
  w->q = *q + 0.5 * h * *qd;
  ForwardDynamics(model, w->q, w->qd2, tau, friction, &w->qdd2);
  w->qd3 = *qd + 0.5 * h * w->qdd2;
  w->q = *q + 0.5 * h * w->qd2;
  ForwardDynamics(model, w->q, w->qd3, tau, friction, &w->qdd3);
  w->qd4 = *qd + h * w->qdd3;
  w->q = *q + h * w->qd3;
  ForwardDynamics(model, w->q, w->qd4, tau, friction, &w->qdd4);
  *q += h / 6 * (*qd + 2 * w->qd2 + 2 * w->qd3 + w->qd4);
  *qd += h / 6 * (w->qdd1 + 2 * w->qdd2 + 2 * w->qdd3 + w->qdd4);
}

}  // namespace

void Rk4Step(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction, ArmStepWorkspace* w,
             Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  ForwardDynamics(model, *q, *qd, tau, friction, &w->qdd1);
  Rk4Stages(model, tau, h, friction, w, q, qd);
}

void Rk4StepFrom(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                 const Eigen::VectorXd& qdd_start, ArmStepWorkspace* w, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  if (qdd_start.size() != model.dof()) throw std::invalid_argument("Rk4StepFrom: qdd_start has the wrong size");
  w->qdd1 = qdd_start;
  Rk4Stages(model, tau, h, friction, w, q, qd);
}

void SemiImplicitEulerStep(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                           ArmStepWorkspace* w, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  ForwardDynamics(model, *q, *qd, tau, friction, &w->qdd1);
  *qd += h * w->qdd1;
  *q += h * *qd;
}

namespace {

// The time derivative of (q, qd, thm, thm') for FlexibleRk4Step.
FlexibleArmState FlexibleDerivative(const ArmModel& plant, const Eigen::VectorXd& drive, const FlexibleArmState& x) {
  const int n = plant.dof();
  FlexibleArmState dx;
  dx.q = x.qd;
  dx.motor_q = Eigen::VectorXd::Zero(n);
  dx.motor_qd = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd tau = drive;
  for (int j = 0; j < n; ++j) {
    const JointEffects e = plant.effects.joint(j);
    if (!e.flexible()) continue;
    const double spring = e.stiffness * (x.motor_q[j] - x.q[j]) + e.flex_damping * (x.motor_qd[j] - x.qd[j]);
    tau[j] = spring;
    dx.motor_q[j] = x.motor_qd[j];
    dx.motor_qd[j] = (drive[j] - spring) / e.motor_inertia;
  }
  dx.qd = ForwardDynamics(plant, x.q, x.qd, tau, /*friction=*/false);
  return dx;
}

// x + a dx.
FlexibleArmState Advance(const FlexibleArmState& x, double a, const FlexibleArmState& dx) {
  return FlexibleArmState{x.q + a * dx.q, x.qd + a * dx.qd, x.motor_q + a * dx.motor_q, x.motor_qd + a * dx.motor_qd};
}

}  // namespace

void FlexibleRk4Step(const ArmModel& plant, const Eigen::VectorXd& drive, double h, FlexibleArmState* x) {
  const int n = plant.dof();
  if (drive.size() != n || x->q.size() != n || x->qd.size() != n || x->motor_q.size() != n ||
      x->motor_qd.size() != n) {
    throw std::invalid_argument("FlexibleRk4Step: a vector has the wrong size");
  }
  const FlexibleArmState k1 = FlexibleDerivative(plant, drive, *x);
  const FlexibleArmState k2 = FlexibleDerivative(plant, drive, Advance(*x, 0.5 * h, k1));
  const FlexibleArmState k3 = FlexibleDerivative(plant, drive, Advance(*x, 0.5 * h, k2));
  const FlexibleArmState k4 = FlexibleDerivative(plant, drive, Advance(*x, h, k3));
  x->q += h / 6 * (k1.q + 2 * k2.q + 2 * k3.q + k4.q);
  x->qd += h / 6 * (k1.qd + 2 * k2.qd + 2 * k3.qd + k4.qd);
  x->motor_q += h / 6 * (k1.motor_q + 2 * k2.motor_q + 2 * k3.motor_q + k4.motor_q);
  x->motor_qd += h / 6 * (k1.motor_qd + 2 * k2.motor_qd + 2 * k3.motor_qd + k4.motor_qd);
}

}  // namespace twinsim
