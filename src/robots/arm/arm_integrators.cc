#include "robots/arm/arm_integrators.h"

#include "robots/arm/arm_dynamics.h"

namespace twinsim {

void Rk4Step(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction, ArmStepWorkspace* w,
             Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  // Stage k's velocity is also the position derivative of stage k (k1q = qd).
  ForwardDynamics(model, *q, *qd, tau, friction, &w->qdd1);
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

void SemiImplicitEulerStep(const ArmModel& model, const Eigen::VectorXd& tau, double h, bool friction,
                           ArmStepWorkspace* w, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  ForwardDynamics(model, *q, *qd, tau, friction, &w->qdd1);
  *qd += h * w->qdd1;
  *q += h * *qd;
}

}  // namespace twinsim
