#include "learning/arm_nominal_step.h"

#include <stdexcept>

#include "backends/arm/arm_backend.h"

namespace twinsim {

ArmNominalStep::ArmNominalStep(const ArmModel& model) : model_(model) {
  if (const std::string problems = model.Validate(); !problems.empty())
    throw std::invalid_argument("arm model '" + model.name + "': " + problems);
  ArmModel undelayed = model;
  undelayed.delay_samples = 0;  // the torques passed in already act
  sim_ = std::make_unique<ArmSimulation>(undelayed, MakeArmBackend("analytic", undelayed));
  const int n = model.dof();
  q_.resize(n);
  qd_.resize(n);
  tau_.resize(n);
}

void ArmNominalStep::Step(const double* q, const double* qd, const double* tau, int samples, double* q_later,
                          double* qd_later) {
  const int n = model_.dof();
  for (int i = 0; i < n; ++i) q_[i] = q[i], qd_[i] = qd[i], tau_[i] = tau[i];
  sim_->Reset(q_, qd_, tau_);
  int k = 0;
  const ArmController acting = [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    for (int i = 0; i < n; ++i) tau_[i] = tau[k * n + i];
    ++k;
    return tau_;
  };
  for (int s = 0; s < samples; ++s) sim_->Step(acting);
  const Eigen::VectorXd& qe = sim_->backend().q();
  const Eigen::VectorXd& qde = sim_->backend().qd();
  for (int i = 0; i < n; ++i) q_later[i] = qe[i], qd_later[i] = qde[i];
}

}  // namespace twinsim
