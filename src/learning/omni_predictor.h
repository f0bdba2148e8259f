// A learned omni robot model: predicts the pose H frames ahead from the last frames
// and the commands (omni_features.h), by ridge regression or a small neural net.
//
// A predictor file (YAML, versioned) says what it was trained on: the robot model's
// name, the frame rate, the feature layout (history, horizon, command lag), the logs
// and the fit. Load() checks the file; CheckUse() refuses a use that does not match
// with a clear message (exit code 2 on the command line).
//
//   OmniPredictor p = TrainOmniPredictor(model, logs, options, &summary);
//   p.Save("blue.pred");
//   OmniPredictor q = OmniPredictor::Load("blue.pred");
//   q.CheckUse(model, 30.0, 1, "the learned backend");
//   Eigen::Vector3d delta = q.PredictDelta(inputs);   // robot frame of the newest pose
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "learning/mlp.h"
#include "learning/omni_features.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

inline constexpr int kPredictorFormatVersion = 2;  // 2: heading as (sin, cos - 1)

struct OmniPredictorInfo {
  std::string kind;           // "linear" or "mlp"
  std::string model_name;     // the robot model it was trained for
  double frame_rate = 0;      // Hz of the logs it was trained on
  FeatureLayout layout;
  std::vector<std::string> logs;  // paths of the training logs
  int samples = 0;                // training + validation samples
  double train_rmse = 0;          // m, position part of the fit on the training split
  double validation_rmse = 0;     // m, on the held-out split (last 20 % of each log)
  double validation_rollout_rmse = 0;  // m, H = 1: the model run on its own for 1 s, held out
};

class OmniPredictor {
 public:
  const OmniPredictorInfo& info() const { return info_; }

  // The pose change (robot frame of the newest pose: dx m, dy m, dtheta rad) for inputs
  // laid out as info().layout says (num_inputs() numbers).
  Eigen::Vector3d PredictDelta(const double* inputs) const;
  // The pose H frames after poses.back(), from `history` poses and num_commands()
  // acting commands (omni_features.h).
  Pose2 Predict(const Pose2* poses, const Twist2* commands) const;

  // Throws InputError naming the file when the predictor was trained for another
  // robot model, frame rate (more than 1 % off) or horizon; `use` names the user.
  void CheckUse(const OmniModel& model, double frame_rate, int horizon, const std::string& use) const;

  // Writes the file atomically.
  void Save(const std::string& path) const;
  // Reads and checks a file; throws InputError "path:line: what is wrong".
  static OmniPredictor Load(const std::string& path);

 private:
  friend OmniPredictor MakeLinearPredictor(OmniPredictorInfo, Eigen::VectorXd, Eigen::VectorXd, Eigen::MatrixXd,
                                           Eigen::Vector3d);
  friend OmniPredictor MakeMlpPredictor(OmniPredictorInfo, Mlp);
  friend OmniPredictor TrainOmniPredictor(const OmniModel&, const std::vector<OmniLog>&, const struct OmniTrainOptions&,
                                          struct OmniTrainSummary*, const std::function<void(int, int, double)>&);

  OmniPredictorInfo info_;
  std::string path_;  // where it was loaded from, for messages
  // linear: delta = weights * ((x - mean) / scale) + bias
  Eigen::VectorXd input_mean_, input_scale_;  // in
  Eigen::MatrixXd weights_;                   // 3 x in
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  Mlp mlp_;
  Eigen::Vector3d mlp_at_rest_ = Eigen::Vector3d::Zero();  // the network's output for all-zero inputs
  mutable Eigen::VectorXd scratch_;           // in, normalised inputs (linear)
};

struct OmniTrainOptions {
  std::string kind = "linear";   // linear | mlp
  int horizon = 1;               // H, frames
  double ridge = 1e-3;           // linear: L2 weight on standardised inputs, per sample
  double validation_fraction = 0.2;  // held out from the end of every log
  MlpOptions mlp;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct OmniTrainSummary {
  int samples = 0;
  int train_samples = 0;
  double train_rmse = 0;       // m
  double validation_rmse = 0;  // m
  double validation_rollout_rmse = 0;  // m, H = 1: the model on its own for 1 s, held out
  double seconds = 0;          // wall time of the fit
  std::string mlp_report;
  std::string BriefReport() const;
};

// Learns a predictor of `model`'s robot from logs (in the contract's format) with the
// model's delay as the command lag. Throws InputError when the logs are too short to
// fill one window, disagree in frame rate, or the options are invalid.
OmniPredictor TrainOmniPredictor(const OmniModel& model, const std::vector<OmniLog>& logs,
                                 const OmniTrainOptions& options, OmniTrainSummary* summary = nullptr,
                                 const std::function<void(int, int, double)>& progress = {});

// The inputs' layout of `model`'s predictors for `horizon` frames: the default history and
// the model's command + vision delay as the command lag. Training, MakeLinearOmniPredictor
// and anyone building training data outside twinsim use this one layout.
FeatureLayout PredictorLayout(const OmniModel& model, int horizon);

// A linear predictor from weights fitted elsewhere (NumPy, another tool): the pose change
// is weights * inputs + bias, inputs laid out as PredictorLayout(model, horizon)
// (omni_features.h; AppendSamples gives the training inputs).
// weights is 3 x num_inputs. Throws InputError for another shape, a horizon outside
// 1..100, a frame rate outside 1..10000 Hz or a number that is not finite.
OmniPredictor MakeLinearOmniPredictor(const OmniModel& model, double frame_rate, int horizon,
                                      const Eigen::MatrixXd& weights, const Eigen::Vector3d& bias);

}  // namespace twinsim
