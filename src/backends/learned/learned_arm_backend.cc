#include "backends/learned/learned_arm_backend.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

class LearnedArmBackend final : public ArmBackend {
 public:
  LearnedArmBackend(const ArmModel& model, const ArmPredictor& predictor)
      : model_(model), predictor_(predictor), layout_(predictor.layout()), n_(model.dof()) {
    // A residual predictor steps the nominal model of `model` under its correction.
    predictor_.AttachModel(model, "the learned arm backend");
    const std::size_t size = static_cast<std::size_t>(layout_.history * n_);
    q_hist_.resize(size);
    qd_hist_.resize(size);
    tau_hist_.resize(size);
    q_.resize(n_);
    qd_.resize(n_);
    Reset(Eigen::VectorXd::Zero(n_), Eigen::VectorXd::Zero(n_), Eigen::VectorXd::Zero(n_));
  }

  std::string name() const override { return "learned"; }
  int dof() const override { return n_; }
  int physics_substeps() const override { return 1; }

  // The commands before t = 0 do not matter: the window starts with the torque the
  // steady motion needs.
  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before) override {
    CheckArmState(name(), n_, q, qd);
    const int h = layout_.history;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n_);
    for (int j = 0; j < h; ++j) {
      // A steady motion at qd that reaches q now.
      const double back = (h - 1 - j) * model_.sample_time;
      const Eigen::VectorXd qj = q - back * qd;
      const Eigen::VectorXd tau = InverseDynamics(model_, qj, qd, zero, /*friction=*/true);
      for (int i = 0; i < n_; ++i) {
        q_hist_[static_cast<std::size_t>(j * n_ + i)] = qj[i];
        qd_hist_[static_cast<std::size_t>(j * n_ + i)] = qd[i];
        tau_hist_[static_cast<std::size_t>(j * n_ + i)] = tau[i];
      }
    }
    q_ = q;
    qd_ = qd;
  }

  void Step(const Eigen::VectorXd& tau, Eigen::VectorXd* applied) override {
    CheckArmStep(name(), n_, tau, model_.sample_time);
    applied->setZero(n_);
    *applied += tau;
    // Shift the window by one sample; the newest torque is the one acting now.
    Shift(&tau_hist_, tau.data());
    predictor_.Predict(q_hist_.data(), qd_hist_.data(), tau_hist_.data(), q_.data(), qd_.data());
    Shift(&q_hist_, q_.data());
    Shift(&qd_hist_, qd_.data());
  }

  const Eigen::VectorXd& q() const override { return q_; }
  const Eigen::VectorXd& qd() const override { return qd_; }

  // The window travels in ArmBackendState::engine (q, qd and the three histories).
  ArmBackendState Save() const override {
    ArmBackendState s;
    ArmEngineState& e = s.engine;
    e.q = q_;
    e.qd = qd_;
    e.exact.reserve(3 * q_hist_.size());
    e.exact.insert(e.exact.end(), q_hist_.begin(), q_hist_.end());
    e.exact.insert(e.exact.end(), qd_hist_.begin(), qd_hist_.end());
    e.exact.insert(e.exact.end(), tau_hist_.begin(), tau_hist_.end());
    return s;
  }

  void Restore(const ArmBackendState& state) override {
    const ArmEngineState& e = state.engine;
    CheckArmState(name(), n_, e.q, e.qd);
    const std::size_t size = q_hist_.size();
    if (e.exact.size() != 3 * size)
      throw std::invalid_argument("learned arm backend: state of another backend or predictor (window of " +
                                  std::to_string(e.exact.size()) + " numbers, expected " +
                                  std::to_string(3 * size) + ")");
    q_hist_.assign(e.exact.begin(), e.exact.begin() + static_cast<long>(size));
    qd_hist_.assign(e.exact.begin() + static_cast<long>(size), e.exact.begin() + static_cast<long>(2 * size));
    tau_hist_.assign(e.exact.begin() + static_cast<long>(2 * size), e.exact.end());
    q_ = e.q;
    qd_ = e.qd;
  }

 private:
  // Drops the oldest row of a history x dof window and appends `row`.
  void Shift(std::vector<double>* window, const double* row) const {
    std::copy(window->begin() + n_, window->end(), window->begin());
    std::copy(row, row + n_, window->end() - n_);
  }

  ArmModel model_;
  ArmPredictor predictor_;
  ArmFeatureLayout layout_;
  int n_;
  std::vector<double> q_hist_, qd_hist_, tau_hist_;  // history x dof, row-major, oldest first
  Eigen::VectorXd q_, qd_;                           // the newest state
};

}  // namespace

std::unique_ptr<ArmBackend> MakeLearnedArmBackend(const ArmModel& model, const ArmPredictor& predictor) {
  if (const std::string problems = model.Validate(); !problems.empty())
    throw InputError("arm model '" + model.name + "': " + problems);
  predictor.CheckUse(model, 1, "the learned arm backend");
  return std::make_unique<LearnedArmBackend>(model, predictor);
}

}  // namespace twinsim
