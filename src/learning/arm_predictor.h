// A learned arm model: predicts the joint state H samples ahead from the last samples
// of joint states and drive torques (arm_features.h), by ridge regression or a small
// neural net (learning/mlp.h). A residual ("hybrid") predictor learns only what the
// nominal physical model of the arm misses: its prediction is the nominal model's step
// (learning/arm_nominal_step.h) plus the learned correction, so it needs that model
// attached (AttachModel; training attaches it) before it predicts. The learned arm backend (backends/learned/
// learned_arm_backend.h) steps an arm with it inside the usual simulation loop.
//
// A predictor file (YAML, versioned, `robot: arm`) says what it was trained on: the arm
// model's name, dof, sample time, the feature layout (joint kinds, history, horizon,
// command lag), the logs and the fit. Load() checks the file (and refuses an omni
// predictor by name); CheckUse() refuses a use that does not match with a clear
// message (exit code 2 on the command line).
//
//   ArmPredictor p = TrainArmPredictor(model, logs, options, &summary);
//   p.Save("rrr.pred");
//   ArmPredictor q = ArmPredictor::Load("rrr.pred");
//   q.CheckUse(model, 1, "the learned arm backend");
//   q.AttachModel(model, "my use");   // a residual predictor needs its nominal model
//   q.Predict(qs, qds, taus, q_next.data(), qd_next.data());
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "learning/arm_features.h"
#include "learning/arm_nominal_step.h"
#include "learning/mlp.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// Version 2 added `residual` (and the nominal model's parameters of a residual
// predictor); version 1 files are read as non-residual predictors.
inline constexpr int kArmPredictorFormatVersion = 2;

struct ArmPredictorInfo {
  std::string kind;               // "linear" or "mlp"
  bool residual = false;          // true: the output corrects the nominal model's step
  std::string model_name;         // the arm model it was trained for
  Eigen::VectorXd nominal_parameters;  // residual only: the model's standard parameters (12 per
                                       // joint, arm_regressor.h) that its nominal step used
  ArmFeatureLayout layout;        // its dof, sample time, history, horizon, command lag
  std::vector<std::string> logs;  // paths of the training logs
  int samples = 0;                // training + validation samples
  double train_rmse = 0;          // rad (or m), q part of the one-step fit on the training split
  double validation_rmse = 0;     // rad, on the held-out split (last part of each log)
  double validation_qd_rmse = 0;  // rad/s, the qd part on the held-out split
  double validation_rollout_rmse = 0;  // rad, H = 1: the model on its own for 100 ms, held out
};

class ArmPredictor {
 public:
  const ArmPredictorInfo& info() const { return info_; }
  const ArmFeatureLayout& layout() const { return info_.layout; }

  bool residual() const { return info_.residual; }

  // The learned outputs (num_outputs(), arm_features.h) for inputs laid out as layout()
  // says; for a residual predictor, the correction to the nominal model's outputs.
  void PredictOutputs(const double* inputs, double* outputs) const;
  // The state H samples after the newest of `history` states q, qd (row-major history x
  // dof, oldest first) under the torques tau (num_torques() x dof): into q_next, qd_next
  // (dof each). Throws std::logic_error for a residual predictor without an attached
  // model, CheckFailed when its nominal model runs away. One predictor object is safe to
  // use from several threads (its nominal step is guarded); copies are independent.
  void Predict(const double* q, const double* qd, const double* tau, double* q_next, double* qd_next) const;

  // Throws InputError naming the file when the predictor was trained for another arm
  // model (name, joint count or kinds), sample time (more than 0.1 % off), delay or
  // horizon, or (residual) for a model whose dynamic or friction parameters differ from
  // the ones its nominal step was trained with; `use` names the user.
  void CheckUse(const ArmModel& model, int horizon, const std::string& use) const;
  // CheckUse(model, layout().horizon, use), then, for a residual predictor, builds its
  // nominal step over `model`. Throws as CheckUse does.
  void AttachModel(const ArmModel& model, const std::string& use);

  // Writes the file atomically.
  void Save(const std::string& path) const;
  // Reads and checks a file; throws InputError "path:line: what is wrong" (an omni
  // robot's predictor is refused as such).
  static ArmPredictor Load(const std::string& path);

 private:
  friend ArmPredictor MakeLinearArmPredictor(ArmPredictorInfo, Eigen::VectorXd, Eigen::VectorXd, Eigen::MatrixXd,
                                             Eigen::VectorXd);
  friend ArmPredictor MakeMlpArmPredictor(ArmPredictorInfo, Mlp);
  friend ArmPredictor TrainArmPredictor(const ArmModel&, const std::vector<ArmLog>&, const struct ArmTrainOptions&,
                                        struct ArmTrainSummary*, const std::function<void(int, int, double)>&);

  // A residual predictor's nominal step; a copy builds its own.
  class NominalSlot {
   public:
    NominalSlot() = default;
    NominalSlot(const NominalSlot& other) { *this = other; }
    NominalSlot& operator=(const NominalSlot& other);
    void Set(const ArmModel& model) { step = std::make_unique<ArmNominalStep>(model); }
    std::unique_ptr<ArmNominalStep> step;
    mutable std::mutex mutex;
  };

  ArmPredictorInfo info_;
  std::string path_;  // where it was loaded from, for messages
  NominalSlot nominal_;
  // linear: y = weights * ((x - mean) / scale) + bias
  Eigen::VectorXd input_mean_, input_scale_;  // in
  Eigen::MatrixXd weights_;                   // out x in
  Eigen::VectorXd bias_;                      // out
  Mlp mlp_;
};

struct ArmTrainOptions {
  std::string kind = "linear";       // linear | mlp
  bool residual = false;             // learn the correction to the nominal model's step
  // Residual only: the nominal model's errors over the history as further inputs
  // (arm_features.h). Unset: on for linear, off for mlp (measured, docs/arm_learning.md).
  std::optional<bool> nominal_errors;
  int history = 4;                   // samples of history (docs/arm_learning.md: chosen by measurement)
  int horizon = 1;                   // H, samples
  double ridge = 1e-9;               // linear: L2 weight on standardised inputs, per sample
  double residual_ridge = 1e-5;      // the same for a residual linear predictor (measured,
                                     // docs/arm_learning.md: damps the gains on the nominal errors)
  double validation_fraction = 0.2;  // held out from the end of every log
  double rollout_seconds = 0.1;      // s, the held-out free-run check (H = 1)
  MlpOptions mlp;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct ArmTrainSummary {
  int samples = 0;
  int train_samples = 0;
  double train_rmse = 0;               // rad, one step, q part
  double validation_rmse = 0;          // rad, one step, q part, held out
  double validation_qd_rmse = 0;       // rad/s, one step, held out
  double validation_rollout_rmse = 0;  // rad, on its own for rollout_seconds, held out (H = 1)
  double seconds = 0;                  // wall time of the fit
  std::string mlp_report;
  std::string BriefReport() const;
};

// Learns a predictor of `model`'s arm from logs in the contract's arm format, with the
// model's delay_samples as the command lag. Throws InputError (naming the log) when a
// log's joint count differs from the model's, its sample period differs from the
// model's sample time by more than 1 %, it is too short for one training window, or the
// options are invalid.
ArmPredictor TrainArmPredictor(const ArmModel& model, const std::vector<ArmLog>& logs, const ArmTrainOptions& options,
                               ArmTrainSummary* summary = nullptr,
                               const std::function<void(int, int, double)>& progress = {});

// Runs the 1-sample predictor on its own from the state at row `start` of `seq` for
// `steps` samples under the logged acting torques; returns the q error (rad) at each
// step (steps x dof). Throws std::invalid_argument when the window does not fit.
Eigen::MatrixXd ArmRolloutError(const ArmPredictor& predictor, const ArmSequence& seq, int start, int steps);

}  // namespace twinsim
