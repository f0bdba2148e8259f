// A learned omni robot model: predicts the pose H frames ahead from the last frames
// and the commands (omni_features.h), by ridge regression or a small neural net.
//
// A residual ("hybrid") predictor (`train --residual`) learns only what the Newtonian
// model misses: its prediction is the model's own (on one of the engines, carried along
// the poses by a NominalOmniTrack, learning/omni_residual.h) plus a learned correction,
// with the model's state and recent errors among its inputs. Where the model is right it
// has little to learn; where it misses an effect it learns the effect.
//
// A predictor file (YAML, versioned) says what it was trained on: the robot model's
// name, the frame rate, the feature layout (history, horizon, command lag), the logs
// and the fit; a residual one also the engine and a fingerprint of the model it
// corrects. Load() checks the file; CheckUse() refuses a use that does not match with a
// clear message (exit code 2 on the command line).
//
//   OmniPredictor p = TrainOmniPredictor(model, logs, options, &summary);
//   p.Save("blue.pred");
//   OmniPredictor q = OmniPredictor::Load("blue.pred");
//   q.CheckUse(model, 30.0, 1, "the learned backend");
//   Eigen::Vector3d delta = q.PredictDelta(inputs);   // robot frame of the newest pose
//   // a residual one, with the model it corrects carried along the poses:
//   NominalOmniTrack track = q.MakeNominalTrack(model);
//   Pose2 next = q.Step(poses, commands, &track);     // H = 1, the track moves along
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "learning/mlp.h"
#include "learning/omni_features.h"
#include "learning/omni_residual.h"
#include "learning/predictor_file.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// 2: heading as (sin, cos - 1). 3: residual predictors (the `nominal` block and the
// layout's `residual`, `nominal_errors`); the seed's predictors are still written as 2,
// so that older builds keep reading them, and those refuse a residual one by its version.
inline constexpr int kPredictorFormatVersion = 2;
inline constexpr int kResidualPredictorFormatVersion = 3;

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
  // The largest pose change over H frames between measured frames of the training logs
  // (m and rad, camera noise included); 0 where unknown (a file from before issue 40).
  // The learned backend holds a step to kBoundFactor times these (BoundStep).
  double max_step = 0, max_turn = 0;
  // Each input's lowest and highest value over the training windows (num_inputs() each);
  // empty where unknown (a file from before). A window with an input beyond them by more
  // than kInputMargin of their span is one the predictor never saw the like of.
  std::vector<double> input_low, input_high;
  // H = 1 predictors trained with a validation split: the driving noise that makes the
  // learned backend's rollouts calibrated on the held-out rows (analysis/learned_noise.h),
  // which the learned backend then draws in place of the model's; absent (`has_driving_noise`
  // false) in files from before issue 42 and for H > 1.
  bool has_driving_noise = false;
  OmniDrivingNoise driving_noise;
  // With the driving noise, its intervals' safeguard (`train`'s conformal scale, fitted on
  // the same held-out rows; docs/learning.md, "The intervals' safeguard"): k frames ahead
  // the sampled rollouts' spread about the prediction is multiplied by `position` and
  // `heading` (IntervalScaleAt; no growths). Empty: the rollouts as drawn.
  std::vector<OmniObserverModel::IntervalScale> interval_scale;
  // Residual predictors (layout.residual) only:
  std::string nominal_engine;       // the engine of the model it corrects: analytic, ode, bullet
  int nominal_substeps = 0;         // that model's physics steps per frame
  // How that model is carried along the poses (NominalOmniTrack): the open-loop tracker
  // (files from before have no word for it) or its observer.
  OmniReplayState nominal_state = OmniReplayState::kTracker;
  std::string nominal_fingerprint;  // NominalModelFingerprint() of that model
};

// How far beyond anything its training logs showed a learned step may go.
inline constexpr double kBoundFactor = 1.5;
// How far beyond the training inputs' range (a share of its span) an input may lie
// before the window counts as unseen.
inline constexpr double kInputMargin = 0.25;

// True when every input lies within `info`'s training range widened by kInputMargin of
// its span (true when the range is unknown).
bool InputsSeen(const OmniPredictorInfo& info, const double* inputs);
// How far the inputs lie beyond `info`'s training range: the largest over the inputs of
// the distance outside [low, high] over the span high - low (an input whose range has no
// span, or a NaN, counts as 1 once it leaves it by more than 1e-9; at most
// kLargestInputExcess); 0 inside, and where the range is unknown. A window beyond
// kInputMargin is one InputsSeen calls unseen.
inline constexpr double kLargestInputExcess = 1e9;
double InputExcess(const OmniPredictorInfo& info, const double* inputs);

// The most networks an ensemble holds (OmniTrainOptions::members).
inline constexpr int kMostEnsembleMembers = 32;

// The pose H frames after `from` that `to` predicts, held to `info`'s bounds: a
// translation longer than kBoundFactor * max_step is shortened along its direction, a
// turn beyond kBoundFactor * max_turn clipped. Sets *bounded when it changed anything.
Pose2 BoundStep(const OmniPredictorInfo& info, const Pose2& from, const Pose2& to, bool* bounded);

class OmniPredictor {
 public:
  const OmniPredictorInfo& info() const { return info_; }

  // The pose change (robot frame of the newest pose: dx m, dy m, dtheta rad) for inputs
  // laid out as info().layout says (num_inputs() numbers).
  Eigen::Vector3d PredictDelta(const double* inputs) const;
  bool residual() const { return info_.layout.residual; }

  // The pose H frames after poses.back(), from `history` poses and num_commands()
  // acting commands (omni_features.h). Throws std::logic_error for a residual predictor,
  // which needs its track (below). With `unseen`, sets it to whether the inputs left the
  // training range (InputsSeen), with `excess` to how far (InputExcess); so do the calls
  // below.
  Pose2 Predict(const Pose2* poses, const Twist2* commands, bool* unseen = nullptr, double* excess = nullptr) const;

  // Residual predictors: the model they correct, ready to be carried along the poses
  // (Reset, then Step and Correct each frame). `model` must have passed CheckUse().
  NominalOmniTrack MakeNominalTrack(const OmniModel& model) const;
  // The pose H frames after poses.back(), `track` standing at that pose (corrected to
  // it); the track is left as it was.
  Pose2 Predict(const Pose2* poses, const Twist2* commands, NominalOmniTrack* track, bool* unseen = nullptr,
                double* excess = nullptr) const;
  // H = 1 on its own: the next pose, and `track` moved on to it (stepped and corrected),
  // ready for the next call. Throws CheckFailed when the nominal model runs away.
  Pose2 Step(const Pose2* poses, const Twist2* commands, NominalOmniTrack* track, bool* unseen = nullptr,
             double* excess = nullptr) const;

  // Throws InputError naming the file when the predictor was trained for another
  // robot model, frame rate (more than 1 % off) or horizon, or (residual) over a model
  // whose parameters differ from `model`'s; `use` names the user.
  void CheckUse(const OmniModel& model, double frame_rate, int horizon, const std::string& use) const;

  // Sets the driving noise the learned backend draws with this predictor (info()).
  void SetDrivingNoise(const OmniDrivingNoise& noise) {
    info_.has_driving_noise = true;
    info_.driving_noise = noise;
  }
  // Sets the safeguard's scales (OmniPredictorInfo::interval_scale; empty: none). They
  // scale the predictor's own driving noise: a predictor without one neither uses nor
  // saves them.
  void SetIntervalScale(std::vector<OmniObserverModel::IntervalScale> scales) {
    info_.interval_scale = std::move(scales);
  }

  // A linear one-frame predictor's weights' own uncertainty (learning/predictor_file.h's
  // RidgeWeightDirections: the fit's covariance from its residuals summed over blocks of a
  // second), as principal directions on the scaled inputs; none for a network, for
  // weights fitted elsewhere and for files from before (docs/learning.md, "The weights'
  // own uncertainty").
  const RidgeWeightUncertainty& weight_uncertainty() const { return weight_uncertainty_; }
  void SetWeightUncertainty(RidgeWeightUncertainty u);
  // Moves this predictor's weights to a draw from `estimate`'s uncertainty: estimate's
  // weights plus sum_l z_l D_l (z: one number per direction). `estimate` is the
  // predictor this one was copied from; the learned backend draws once per rollout.
  void DrawWeights(const OmniPredictor& estimate, const Eigen::VectorXd& z);
  // A network's further members (OmniTrainOptions::members; the network itself is member
  // 0), empty for a linear predictor and a network alone.
  const std::vector<Mlp>& ensemble() const { return ensemble_; }
  void SetEnsemble(std::vector<Mlp> members);
  // Moves this predictor's network to `estimate`'s member k (0: its own network), as
  // DrawWeights does for a linear predictor's weights.
  void DrawMember(const OmniPredictor& estimate, int k);

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
  RidgeWeightUncertainty weight_uncertainty_;  // directions 3 x in, like weights_
  // A residual predictor's pose: the nominal model's prediction `nominal_end` of the pose
  // H frames after poses[history - 1], corrected; `nominal_velocity` and `errors` are the
  // model's at poses[history - 1].
  Pose2 Corrected(const Pose2* poses, const Twist2* commands, const Twist2& nominal_velocity, const Pose2& nominal_end,
                  const std::vector<Eigen::Vector3d>& errors, bool* unseen, double* excess) const;

  Mlp mlp_;
  Eigen::Vector3d mlp_at_rest_ = Eigen::Vector3d::Zero();  // the network's output for all-zero inputs
  std::vector<Mlp> ensemble_;  // members 1.. (OmniTrainOptions::members)
  std::vector<Eigen::Vector3d> ensemble_at_rest_;  // each member's output for all-zero inputs
};

// The rows of each log a predictor is validated on: its last `fraction` of frames, as
// TrainOmniPredictor splits them (OmniTrainOptions::validation_fraction), each as a log of
// its own; logs with fewer than two rows there are left out.
std::vector<OmniLog> OmniValidationParts(const std::vector<OmniLog>& logs, double fraction);

// The driving noise a robot of `model` draws on the learned backend with `predictor`
// (null: none): the predictor's own where it has one (`train` fits it), else the model's.
const OmniDrivingNoise& LearnedDrivingNoise(const OmniModel& model, const OmniPredictor* predictor);

struct OmniTrainOptions {
  std::string kind = "linear";   // linear | mlp
  int horizon = 1;               // H, frames
  bool residual = false;         // learn the correction to the Newtonian model's prediction
  std::string nominal_engine = "analytic";  // residual: the engine that model runs on
  // Residual: how that model is carried along the poses: by its observer (the estimate a
  // physics-only replay starts from) or the open-loop tracker (NominalOmniTrack). With
  // `choose_nominal_state`, both are trained and the one whose held-out rollouts (1 s from
  // the validation rows) come nearer is kept, the tracker where they tie: neither wins
  // everywhere (docs/learning.md, "The observer's track").
  OmniReplayState nominal_state = OmniReplayState::kTracker;
  bool choose_nominal_state = false;
  // Residual: that model's physics steps per frame; 0 chooses: for the tracker 2 on
  // analytic (at 30 fps it predicts as well as the loop's 10 at a fifth of the cost), the
  // loop's on ode and bullet (whose contacts need it); for the observer the loop's on every
  // engine (its predictions ahead run uncorrected from its estimate, where a coarser step
  // is another model; measured in docs/learning.md).
  int nominal_substeps = 0;
  // Residual: the model's last one-frame errors among the inputs. 0 by default: on logs
  // with camera noise they made every predictor measured worse (docs/learning.md).
  int nominal_errors = 0;
  double ridge = 1e-3;  // linear: L2 weight on standardised inputs, per sample (the seed's)
  // A residual linear predictor's ridges instead, tried per output (forward, sideways,
  // turn) with no correction at all, and chosen by cross-validation over the logs (one
  // log: stretches of its time) by the one-standard-error rule (FitResidualChoosingRidge
  // in omni_predictor.cc): where nothing learned clearly helps a left-out log, the hybrid
  // is its physics alone, never worse than it there.
  std::vector<double> residual_ridges = {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3, 1e4};
  double validation_fraction = 0.2;  // held out from the end of every log
  // Per log, per row: may a sample (its window of poses and its target) use the row?
  // Empty: every row. The diagnosis marks its fit blocks, so that its learned yardstick
  // sees no held-out row while a residual's nominal track runs along the whole log.
  std::vector<std::vector<char>> sample_rows;
  MlpOptions mlp;
  // A network: how many networks to train, the first on the training windows as they are,
  // each further one from its own start on a block bootstrap of them (whole seconds drawn
  // with replacement). The first predicts; sampled rollouts each draw one of them, so that
  // the networks' disagreement (largest where the inputs leave the training's) widens the
  // intervals (docs/learning.md, "An ensemble of networks"). 1: the network alone.
  int members = 1;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// A residual linear predictor's corrections checked by its 1 s rollouts, cross-validated
// over the ridge's folds (omni_predictor.cc's CheckCorrectionsByRollouts). Bit j of a mask
// is output j (forward, sideways, turn).
struct OmniRolloutCheck {
  int chosen = 0;  // the outputs the one-frame cross-validation corrects
  int kept = 0;    // those the rollouts keep
  int folds = 0;   // folds with rollouts; fewer than 2: not checked, every correction kept
  // The left-out folds' 1 s rollouts' RMS position error (m) with the corrections chosen,
  // with those kept, with none (the physics alone).
  double rmse_chosen = 0, rmse_kept = 0, rmse_none = 0;
  // What it did in words ("1 s rollouts over the 4 folds drop the sideways correction
  // (4.21 mm with, 2.85 mm without)"); empty where nothing was checked.
  std::string Describe() const;
};

struct OmniTrainSummary {
  int samples = 0;
  int train_samples = 0;
  double train_rmse = 0;       // m
  double validation_rmse = 0;  // m
  double validation_rollout_rmse = 0;  // m, H = 1: the model on its own for 1 s, held out
  // A residual linear predictor: the ridge chosen per output (forward, sideways, turn) by
  // cross-validation over `ridge_folds` (several logs: one fold each; one log: five
  // stretches of its time); infinite where it keeps no correction (none predicted a
  // left-out fold clearly better than the physics alone). Zero otherwise.
  Eigen::Vector3d ridge = Eigen::Vector3d::Zero();
  std::string ridge_folds;
  // Those corrections checked by the rollouts (`ridge` is infinite where one was dropped).
  OmniRolloutCheck rollout_check;
  // Both in words ("ridge chosen by cross-validation over 4 logs (forward, sideways, turn):
  // no correction, 10, no correction; 1 s rollouts over the 4 folds keep ..."); empty for
  // a predictor without them.
  std::string RidgeChoice() const;
  // A residual predictor whose nominal state was chosen (OmniTrainOptions::
  // choose_nominal_state): each state's held-out 1 s rollout RMSE (m; 0 where not tried),
  // the state kept, and why a state could not be trained (empty: both were).
  double rollout_rmse_observer = 0, rollout_rmse_tracker = 0;
  bool chosen_state = false;
  OmniReplayState kept_state = OmniReplayState::kTracker;
  std::string untrained_state;
  // Whether those rollouts keep the observer: both rolled out, the observer nearer (a
  // tie, or a state without rollouts, keeps the tracker).
  bool KeepsObserver() const {
    return rollout_rmse_observer > 0 && rollout_rmse_tracker > 0 && rollout_rmse_observer < rollout_rmse_tracker;
  }
  // The choice in words ("the model carried by its observer (held-out 1 s rollouts ...)");
  // empty where none was made.
  std::string StateChoice() const;
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
