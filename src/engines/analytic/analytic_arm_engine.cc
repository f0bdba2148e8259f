#include "engines/analytic/analytic_arm_engine.h"

#include <stdexcept>

#include "robots/arm/arm_integrators.h"

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
    for (int i = 0; i < n; ++i) Rk4Step(plant_, tau, h, /*friction=*/false, &work_, &q_, &qd_);
  }

  // The caller's accelerations serve the first internal step's first stage.
  void StepFromAcceleration(const Eigen::VectorXd& tau, double dt, const Eigen::VectorXd& qdd) override {
    CheckArmStep(name(), dof(), tau, dt);
    const int n = ArmSubsteps(dt, max_step_);
    const double h = dt / n;
    Rk4StepFrom(plant_, tau, h, /*friction=*/false, qdd, &work_, &q_, &qd_);
    for (int i = 1; i < n; ++i) Rk4Step(plant_, tau, h, /*friction=*/false, &work_, &q_, &qd_);
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
  ArmModel plant_;
  double max_step_;  // s
  Eigen::VectorXd q_, qd_;
  ArmStepWorkspace work_;  // RK4's stages, kept so that a step allocates nothing
};

}  // namespace

std::unique_ptr<ArmEngine> MakeAnalyticArmEngine(const ArmModel& plant, const ArmEngineOptions& options) {
  const double max_step = options.max_step > 0 ? options.max_step : DefaultArmMaxStep("analytic");
  return std::make_unique<AnalyticArmEngine>(plant, max_step);
}

}  // namespace twinsim
