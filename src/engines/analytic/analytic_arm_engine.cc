#include "engines/analytic/analytic_arm_engine.h"

#include <stdexcept>

#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

class AnalyticArmEngine final : public ArmEngine {
 public:
  AnalyticArmEngine(const ArmModel& plant, double max_step)
      : plant_(plant), max_step_(max_step), q_(Eigen::VectorXd::Zero(plant.dof())), qd_(q_) {}

  std::string name() const override { return "analytic"; }
  int dof() const override { return plant_.dof(); }

  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) override {
    CheckArmState(name(), dof(), q, qd);
    q_ = q;
    qd_ = qd;
  }

  void Step(const Eigen::VectorXd& tau, double dt) override {
    CheckArmStep(name(), dof(), tau, dt);
    const int n = ArmSubsteps(dt, max_step_);
    const double h = dt / n;
    for (int i = 0; i < n; ++i) Rk4(tau, h);
  }

  const Eigen::VectorXd& q() const override { return q_; }
  const Eigen::VectorXd& qd() const override { return qd_; }

  ArmEngineState Save() const override { return ArmEngineState{q_, qd_, {}}; }
  void Restore(const ArmEngineState& state) override {
    CheckArmState(name(), dof(), state.q, state.qd);
    if (!state.exact.empty()) throw std::invalid_argument("analytic arm backend: state of another backend");
    q_ = state.q;
    qd_ = state.qd;
  }

 private:
  Eigen::VectorXd Accel(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau) const {
    return ForwardDynamics(plant_, q, qd, tau, /*friction=*/false);
  }

  // One classical RK4 step of h seconds of (q, qd)' = (qd, qdd(q, qd, tau)).
  void Rk4(const Eigen::VectorXd& tau, double h) {
    const Eigen::VectorXd k1q = qd_;
    const Eigen::VectorXd k1v = Accel(q_, qd_, tau);
    const Eigen::VectorXd k2q = qd_ + 0.5 * h * k1v;
    const Eigen::VectorXd k2v = Accel(q_ + 0.5 * h * k1q, k2q, tau);
    const Eigen::VectorXd k3q = qd_ + 0.5 * h * k2v;
    const Eigen::VectorXd k3v = Accel(q_ + 0.5 * h * k2q, k3q, tau);
    const Eigen::VectorXd k4q = qd_ + h * k3v;
    const Eigen::VectorXd k4v = Accel(q_ + h * k3q, k4q, tau);
    q_ += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
    qd_ += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }

  ArmModel plant_;
  double max_step_;  // s
  Eigen::VectorXd q_, qd_;
};

}  // namespace

std::unique_ptr<ArmEngine> MakeAnalyticArmEngine(const ArmModel& plant, const ArmEngineOptions& options) {
  const double max_step = options.max_step > 0 ? options.max_step : DefaultArmMaxStep("analytic");
  return std::make_unique<AnalyticArmEngine>(plant, max_step);
}

}  // namespace twinsim
