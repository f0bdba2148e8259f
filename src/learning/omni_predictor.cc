#include "learning/omni_predictor.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/rng.h"
#include "io/yaml_reader.h"
#include "learning/cross_validated_ridge.h"
#include "learning/predictor_file.h"
#include "robots/omni/omni_effects.h"

namespace twinsim {

OmniPredictor MakeLinearPredictor(OmniPredictorInfo info, Eigen::VectorXd mean, Eigen::VectorXd scale,
                                  Eigen::MatrixXd weights, Eigen::Vector3d bias) {
  OmniPredictor p;
  p.info_ = std::move(info);
  p.input_mean_ = std::move(mean);
  p.input_scale_ = std::move(scale);
  p.weights_ = std::move(weights);
  p.bias_ = bias;
  return p;
}

FeatureLayout PredictorLayout(const OmniModel& model, int horizon) {
  FeatureLayout layout;
  layout.horizon = horizon;
  layout.command_lag = model.command_delay_frames + model.vision_delay_frames;
  return layout;
}

OmniPredictor MakeLinearOmniPredictor(const OmniModel& model, double frame_rate, int horizon,
                                      const Eigen::MatrixXd& weights, const Eigen::Vector3d& bias) {
  if (horizon < 1 || horizon > 100) throw InputError("linear predictor: horizon must be 1 to 100 frames, got " + std::to_string(horizon));
  if (!(frame_rate >= 1 && frame_rate <= 1e4)) {
    std::ostringstream msg;
    msg << "linear predictor: frame rate must be 1 to 10000 Hz, got " << frame_rate;
    throw InputError(msg.str());
  }
  OmniPredictorInfo info;
  info.kind = "linear";
  info.model_name = model.name;
  info.frame_rate = frame_rate;
  info.layout = PredictorLayout(model, horizon);
  const int inputs = info.layout.num_inputs();
  if (weights.rows() != 3 || weights.cols() != inputs) {
    throw InputError("linear predictor: weights must be 3 x " + std::to_string(inputs) + " for horizon " +
                     std::to_string(horizon) + ", got " + std::to_string(weights.rows()) + " x " +
                     std::to_string(weights.cols()));
  }
  if (!weights.allFinite() || !bias.allFinite()) throw InputError("linear predictor: weights and bias must be finite");
  info.logs.push_back("(fitted outside twinsim)");
  return MakeLinearPredictor(info, Eigen::VectorXd::Zero(inputs), Eigen::VectorXd::Ones(inputs), weights, bias);
}

OmniPredictor MakeMlpPredictor(OmniPredictorInfo info, Mlp mlp) {
  OmniPredictor p;
  p.info_ = std::move(info);
  p.mlp_ = std::move(mlp);
  // A robot at rest with zero commands stays at rest: the network's answer there is
  // subtracted everywhere (training puts it near zero already).
  p.mlp_at_rest_ = p.mlp_.Predict(Eigen::VectorXd::Zero(p.info_.layout.num_inputs()));
  return p;
}

namespace {

double PositionRmse(const Eigen::MatrixXd& predicted, const Eigen::MatrixXd& truth) {
  if (truth.rows() == 0) return 0;
  return std::sqrt((predicted.leftCols(2) - truth.leftCols(2)).rowwise().squaredNorm().mean());
}

}  // namespace

namespace {

// The first frame of a log of `frames` frames that validates (the last `fraction` of them).
int ValidationCut(int frames, double fraction) { return static_cast<int>(std::round(frames * (1 - fraction))); }

}  // namespace

const OmniDrivingNoise& LearnedDrivingNoise(const OmniModel& model, const OmniPredictor* predictor) {
  return predictor && predictor->info().has_driving_noise ? predictor->info().driving_noise : model.driving_noise;
}

std::vector<OmniLog> OmniValidationParts(const std::vector<OmniLog>& logs, double fraction) {
  std::vector<OmniLog> parts;
  for (const OmniLog& log : logs) {
    const int cut = ValidationCut(log.FrameIndex(log.rows.size() - 1) + 1, fraction);
    std::size_t first = 0;
    while (first < log.rows.size() && log.FrameIndex(first) < cut) ++first;
    if (log.rows.size() - first >= 2) parts.push_back(SliceOmniLog(log, first, log.rows.size()));
  }
  return parts;
}

namespace {

// Where a rollout of a residual predictor starts: the frame, its track's state, and the
// index of the window ending there among its log's windows (time order).
struct ResidualStart {
  int frame = 0;
  NominalTrackState track;
  int window = 0;
};

// One log's frames, split in time: windows ending before `cut` train, the rest validate.
struct SplitLog {
  FrameSequence seq;
  int cut = 0;
  std::vector<ResidualStart> residual_starts;  // residual predictors: the held-out rollouts' starts
  std::vector<ResidualStart> check_starts;     // and the rollout check's, over the whole log
  int train_windows = 0, validation_windows = 0;  // the windows it gave each dataset
};

// The rollout check's starts (a residual's corrections checked by cross-validated 1 s
// rollouts): about this many over all logs, evenly spaced.
constexpr int kRolloutCheckStarts = 400;

// Runs the 1-frame model on its own from every window ending in [first, last - frames],
// `frames` steps under the logged acting commands; returns the summed squared position
// error over all steps and their count.
std::pair<double, long> Rollouts(const OmniPredictor& model, const FrameSequence& seq, int first, int last,
                                 int frames) {
  const FeatureLayout& layout = model.info().layout;
  const int h = layout.history;
  std::vector<Pose2> window(static_cast<std::size_t>(h));
  Eigen::VectorXd x(layout.num_inputs());
  double sum = 0;
  long count = 0;
  for (int s = std::max(first, seq.first_known_command + h - 1); s + frames <= last; ++s) {
    if (!seq.Complete(s - h + 1, s + frames) || !seq.Sampled(s - h + 1, s + frames)) continue;
    for (int j = 0; j < h; ++j) window[static_cast<std::size_t>(j)] = seq.pose[static_cast<std::size_t>(s - h + 1 + j)];
    for (int t = 0; t < frames; ++t) {
      const int i = s + t;
      EncodeInputs(layout, window.data(), &seq.acting[static_cast<std::size_t>(i - h + 1)], x.data());
      const Pose2& truth = seq.pose[static_cast<std::size_t>(i + 1)];
      const Pose2 next = ApplyDelta(window.back(), model.PredictDelta(x.data()));
      window.erase(window.begin());
      window.push_back(next);
      sum += std::pow(next.x - truth.x, 2) + std::pow(next.y - truth.y, 2);
      ++count;
    }
  }
  return {sum, count};
}

// A residual predictor's samples from one log (part->seq): the nominal model is carried
// along the measured poses (NominalOmniTrack) from the first frame with a known command
// and a frame before it, and a window ending at frame i is a sample once the track has
// run kNominalWarmUpFrames: into *train when i + H < part->cut, into *validation when
// i >= cut. A window that is measured, with `rollout_frames` sampled frames after it, is a
// rollout start: every `stride`-th validation window into part->residual_starts, every
// `check_stride`-th window into part->check_starts. Returns the number of samples.
int AppendResidualSamples(const FeatureLayout& layout, double frame_rate, NominalOmniTrack* track, int rollout_frames,
                          int stride, int check_stride, SplitLog* part, OmniDataset* train, OmniDataset* validation) {
  const FrameSequence& seq = part->seq;
  const int cut = part->cut;
  const int h = layout.history, horizon = layout.horizon, frames = seq.frames();
  int f0 = std::max(seq.first_known_command, 1);
  while (f0 < frames && !(seq.observed[static_cast<std::size_t>(f0)] && seq.observed[static_cast<std::size_t>(f0 - 1)])) ++f0;
  if (f0 >= frames) return 0;
  const Pose2& b = seq.pose[static_cast<std::size_t>(f0)];
  track->Reset(b, BodyVelocityBetween(seq.pose[static_cast<std::size_t>(f0 - 1)], b, frame_rate));

  const int in = layout.num_inputs();
  std::vector<double> train_x, train_y, val_x, val_y;
  std::vector<double> row(static_cast<std::size_t>(in));
  int validation_windows = 0, windows = 0;
  for (int f = f0; f < frames; ++f) {
    const auto uf = static_cast<std::size_t>(f);
    if (seq.observed[uf]) track->Correct(seq.pose[uf]);
    const int start = f - h + 1;
    const bool usable = f >= f0 + kNominalWarmUpFrames && start >= seq.first_known_command && f + horizon < frames &&
                        seq.Usable(start, f) && seq.observed[static_cast<std::size_t>(f + horizon)] &&
                        seq.Sampled(start, f + horizon);
    const bool for_training = usable && f + horizon < cut;
    const bool for_validation = usable && f >= cut;
    bool stepped = false;
    if (for_training || for_validation) {
      // A rollout needs its start window measured; along it, only measured frames score
      // (ResidualRollouts), so that logs with lost or repeated frames have rollouts too.
      const bool can_roll = seq.Complete(start, f) && f + rollout_frames < frames && seq.Sampled(start, f + rollout_frames);
      const bool held_start = for_validation && validation_windows++ % stride == 0 && can_roll;
      const bool check_start = windows % check_stride == 0 && can_roll;
      if (held_start || check_start) {
        const ResidualStart here{f, track->Save(), windows};
        if (held_start) part->residual_starts.push_back(here);
        if (check_start) part->check_starts.push_back(here);
      }
      ++windows;
      const Pose2& now = seq.pose[uf];
      const Twist2 velocity = track->velocity();
      const std::vector<Eigen::Vector3d> errors = track->errors();
      Pose2 end;
      if (horizon == 1) {
        end = track->Step(seq.acting[uf]);
        stepped = true;
      } else {
        end = track->Lookahead(&seq.acting[uf], horizon);
      }
      const Eigen::Vector3d nominal =
          EncodeResidualInputs(layout, &seq.pose[static_cast<std::size_t>(start)],
                               &seq.acting[static_cast<std::size_t>(start)], end, velocity, errors, row.data());
      Eigen::Vector3d y = EncodeDelta(now, seq.pose[static_cast<std::size_t>(f + horizon)]) - nominal;
      y[2] = WrapAngle(y[2]);
      std::vector<double>& xs = for_training ? train_x : val_x;
      std::vector<double>& ys = for_training ? train_y : val_y;
      xs.insert(xs.end(), row.begin(), row.end());
      ys.insert(ys.end(), y.data(), y.data() + 3);
    }
    if (!stepped && f + 1 < frames) track->Step(seq.acting[uf]);
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  auto append = [&](const std::vector<double>& xs, const std::vector<double>& ys, OmniDataset* data) {
    const long n = static_cast<long>(ys.size() / 3);
    const Eigen::MatrixXd x = Eigen::Map<const RowMajor>(xs.data(), n, in);
    const Eigen::MatrixXd y = Eigen::Map<const RowMajor>(ys.data(), n, 3);
    AppendRows(x, y, data);
    return static_cast<int>(n);
  };
  return append(train_x, train_y, train) + append(val_x, val_y, validation);
}

// The residual 1-frame predictor on its own for `frames` frames from each start (its
// track restored there) under the logged acting commands: the summed squared position
// error over the steps that end on a measured frame, and their count.
std::pair<double, long> ResidualRollouts(const OmniPredictor& model, const FrameSequence& seq,
                                         const std::vector<ResidualStart>& starts, int frames, NominalOmniTrack* track) {
  const int h = model.info().layout.history;
  std::vector<Pose2> window(static_cast<std::size_t>(h));
  double sum = 0;
  long count = 0;
  for (const ResidualStart& s : starts) {
    track->Restore(s.track);
    for (int j = 0; j < h; ++j) window[static_cast<std::size_t>(j)] = seq.pose[static_cast<std::size_t>(s.frame - h + 1 + j)];
    for (int t = 0; t < frames; ++t) {
      const int i = s.frame + t;
      const Pose2 next = model.Step(window.data(), &seq.acting[static_cast<std::size_t>(i - h + 1)], track);
      const Pose2& truth = seq.pose[static_cast<std::size_t>(i + 1)];
      window.erase(window.begin());
      window.push_back(next);
      if (!seq.observed[static_cast<std::size_t>(i + 1)]) continue;
      sum += std::pow(next.x - truth.x, 2) + std::pow(next.y - truth.y, 2);
      ++count;
    }
  }
  return {sum, count};
}

}  // namespace

namespace {

// The predictor's description before any fit: its kind, the model, the frame rate and
// the inputs' layout; a residual predictor's nominal model, with the track that runs it
// into *track.
OmniPredictorInfo StartInfo(const OmniModel& model, const std::vector<OmniLog>& logs, const OmniTrainOptions& options,
                            std::unique_ptr<NominalOmniTrack>* track) {
  OmniPredictorInfo info;
  info.kind = options.kind;
  info.model_name = model.name;
  info.frame_rate = 1.0 / logs[0].frame_period;
  info.layout = PredictorLayout(model, options.horizon);
  if (options.residual) {
    info.layout.residual = true;
    info.layout.nominal_errors = options.nominal_errors;
    info.nominal_engine = options.nominal_engine;
    info.nominal_state = options.nominal_state;
    info.nominal_fingerprint = NominalModelFingerprint(model);
    info.nominal_substeps = options.nominal_substeps > 0 ? options.nominal_substeps
                            : info.nominal_engine == "analytic" && options.nominal_state == OmniReplayState::kTracker
                                ? std::max(1, DefaultPhysicsSubsteps(info.frame_rate) / 5)
                                : DefaultPhysicsSubsteps(info.frame_rate);
    *track = std::make_unique<NominalOmniTrack>(model, info.nominal_engine, info.frame_rate, info.nominal_substeps,
                                                info.layout.nominal_errors, info.nominal_state);
  }
  return info;
}

// The frames of `log` a sample may use: those of its rows marked in `rows` (one per
// row), and the frames without a row after each (they take the row before's mark).
void SetSampledFrames(const OmniLog& log, const std::vector<char>& rows, FrameSequence* seq) {
  seq->sampled.assign(static_cast<std::size_t>(seq->frames()), 0);
  for (std::size_t i = 0; i < log.rows.size() && i < rows.size(); ++i) {
    const int from = log.FrameIndex(i);
    const int to = i + 1 < log.rows.size() ? log.FrameIndex(i + 1) : seq->frames();
    for (int f = from; f < to && f < seq->frames(); ++f) seq->sampled[static_cast<std::size_t>(f)] = rows[i];
  }
}

// Per log: the first part trains, the last part validates (time order kept). Throws
// InputError for a log of another frame rate or too short to give windows to both.
std::vector<SplitLog> SplitLogs(const std::vector<OmniLog>& logs, const OmniTrainOptions& options, int rollout_frames,
                                NominalOmniTrack* track, OmniPredictorInfo* info, OmniDataset* train,
                                OmniDataset* validation) {
  std::vector<SplitLog> split;
  int total_train = 0, total_val = 0;
  std::size_t total_rows = 0;
  if (!options.sample_rows.empty() && options.sample_rows.size() != logs.size())
    throw std::invalid_argument("OmniTrainOptions::sample_rows: one row mask per log");
  std::size_t all_rows = 0;
  for (const OmniLog& log : logs) all_rows += log.rows.size();
  const int check_stride = std::max(1, static_cast<int>(all_rows / kRolloutCheckStarts));
  for (std::size_t k = 0; k < logs.size(); ++k) {
    const OmniLog& log = logs[k];
    if (std::abs(1.0 / log.frame_period - info->frame_rate) > kSameCameraRate * info->frame_rate) {
      std::ostringstream msg;
      msg << "frame rate " << 1.0 / log.frame_period << " fps differs from the first log's " << info->frame_rate << " fps";
      throw InputError(SourceLocation{log.path}, msg.str());
    }
    SplitLog part{ToFrameSequence(log, info->layout), 0, {}, {}, 0, 0};
    if (!options.sample_rows.empty()) SetSampledFrames(log, options.sample_rows[k], &part.seq);
    part.cut = ValidationCut(part.seq.frames(), options.validation_fraction);
    int n_train = 0, n_val = 0;
    if (track) {
      const int before_train = train->rows(), before_val = validation->rows();
      const int stride = std::max(1, (part.seq.frames() - part.cut) / 2000);  // bounds the rollouts' cost
      AppendResidualSamples(info->layout, info->frame_rate, track, rollout_frames, stride, check_stride, &part, train,
                            validation);
      n_train = train->rows() - before_train;
      n_val = validation->rows() - before_val;
    } else {
      n_train = AppendSamples(part.seq, info->layout, 0, part.cut - 1 - info->layout.horizon, train);
      n_val = AppendSamples(part.seq, info->layout, part.cut, part.seq.frames() - 1, validation);
    }
    // Logs are pooled: a short stretch between missed frames gives what windows it has,
    // and only all logs together must give enough (a real camera's log, cut into the fit
    // blocks of a diagnosis, has stretches too short to train on alone).
    total_train += n_train;
    total_val += n_val;
    total_rows += log.rows.size();
    if (n_train + n_val == 0) continue;
    part.train_windows = n_train;
    part.validation_windows = n_val;
    info->logs.push_back(log.path);
    split.push_back(std::move(part));
  }
  if (total_train < 10 || total_val < 1) {
    const int needed = info->layout.history + info->layout.command_lag + info->layout.horizon;
    const std::string what = std::to_string(total_rows) + " rows" +
                             (logs.size() > 1 ? " of " + std::to_string(logs.size()) + " logs" : std::string()) +
                             " give " + std::to_string(total_train) + " training and " + std::to_string(total_val) +
                             " held-out windows (" + std::to_string(needed) +
                             " consecutive frames each, a few missed frames bridged; at least 10 to train on and 1 "
                             "held out are needed)";
    if (logs.size() == 1) throw InputError(SourceLocation{logs.front().path}, "log too short: " + what);
    throw InputError("logs too short: " + what);
  }
  return split;
}

// The inputs' range over the training windows, and the bounds: the largest pose change
// over the horizon between measured frames.
void RangesAndBounds(const OmniDataset& train, const std::vector<SplitLog>& split, OmniPredictorInfo* info) {
  if (train.rows() > 0) {
    info->input_low.resize(static_cast<std::size_t>(train.x.cols()));
    info->input_high.resize(static_cast<std::size_t>(train.x.cols()));
    for (long j = 0; j < train.x.cols(); ++j) {
      info->input_low[static_cast<std::size_t>(j)] = train.x.col(j).minCoeff();
      info->input_high[static_cast<std::size_t>(j)] = train.x.col(j).maxCoeff();
    }
  }
  for (const SplitLog& part : split) {
    const FrameSequence& seq = part.seq;
    for (int f = 0; f + info->layout.horizon < seq.frames(); ++f) {
      const auto a = static_cast<std::size_t>(f), b = static_cast<std::size_t>(f + info->layout.horizon);
      if (!seq.observed[a] || !seq.observed[b] || !seq.Sampled(f, f + info->layout.horizon)) continue;
      const Eigen::Vector3d d = EncodeDelta(seq.pose[a], seq.pose[b]);
      info->max_step = std::max(info->max_step, std::hypot(d[0], d[1]));
      info->max_turn = std::max(info->max_turn, std::abs(WrapAngle(d[2])));
    }
  }
}

// The predictor's pose change for every window of `d` (rows x 3).
Eigen::MatrixXd PredictAll(const OmniPredictor& predictor, const OmniDataset& d) {
  Eigen::MatrixXd out(d.rows(), 3);
  for (int i = 0; i < d.rows(); ++i) {
    const Eigen::VectorXd row = d.x.row(i).transpose();
    out.row(i) = predictor.PredictDelta(row.data()).transpose();
  }
  return out;
}

// With one log, the ridge's cross-validation folds are this many stretches of its time.
constexpr int kRidgeStretches = 5;

// Which fold of the ridge's cross-validation each window belongs to, the training
// windows of all parts first, then the held-out ones (as in JoinedWindows): one fold a log
// where there are several (a new log is what a predictor meets next: another direction,
// another day), else kRidgeStretches stretches of the one log's time.
std::vector<int> RidgeFolds(const std::vector<SplitLog>& split) {
  std::vector<int> fold;
  if (split.size() >= 2) {
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t k = 0; k < split.size(); ++k)
        fold.insert(fold.end(), static_cast<std::size_t>(pass == 0 ? split[k].train_windows : split[k].validation_windows),
                    static_cast<int>(k));
    return fold;
  }
  const int n = split.empty() ? 0 : split[0].train_windows + split[0].validation_windows;
  for (int i = 0; i < n; ++i) fold.push_back(static_cast<int>(static_cast<long>(kRidgeStretches) * i / n));
  return fold;
}

// The training windows followed by the held-out ones.
OmniDataset JoinedWindows(const OmniDataset& train, const OmniDataset& validation) {
  OmniDataset all = train;
  if (validation.rows() > 0) AppendRows(validation.x, validation.y, &all);
  return all;
}

// What the rollout check of a residual's corrections runs on: the logs with their check
// starts, the track that carries the model, and the rollouts' length (frames). No track:
// no check.
struct ResidualCheckInputs {
  const std::vector<SplitLog>* split = nullptr;
  NominalOmniTrack* track = nullptr;
  int frames = 0;
};

// A residual linear predictor's choice: each output's ridge (infinite: no correction) and
// the rollout check that may have dropped some.
struct ResidualChoice {
  Eigen::Vector3d ridge = Eigen::Vector3d::Zero();
  OmniRolloutCheck check;
};

// The check starts of each of `folds` cross-validation folds (RidgeFolds) and the log
// they lie in: with several logs the k-th log's, with one the windows of its k-th
// stretch of time.
struct FoldStarts {
  const SplitLog* part = nullptr;
  std::vector<ResidualStart> starts;
};
std::vector<FoldStarts> StartsByFold(const std::vector<SplitLog>& split, int folds) {
  std::vector<FoldStarts> out(static_cast<std::size_t>(folds));
  for (std::size_t k = 0; k < out.size() && !split.empty(); ++k) {
    const SplitLog& part = split[split.size() >= 2 ? k : 0];
    out[k].part = &part;
    if (split.size() >= 2) {
      out[k].starts = part.check_starts;
      continue;
    }
    const long n = part.train_windows + part.validation_windows;
    for (const ResidualStart& s : part.check_starts)
      if (static_cast<std::size_t>(static_cast<long>(kRidgeStretches) * s.window / n) == k) out[k].starts.push_back(s);
  }
  return out;
}

// Checks a residual's corrections by its rollouts, cross-validated over the ridge's folds
// (ChooseOutputsByFoldCost): for every subset of the outputs the one-frame choice corrects
// (`ridges` finite), the left-out fold's 1 s rollouts' mean squared position error with
// the corrections fitted on the other folds; the subset with the least mean over the
// folds is kept. The one-frame choice is already conservative (its one-standard-error
// rule), so this check only drops what makes the rollouts worse: a correction that wins a
// frame can lose a second, where its small errors compound (docs/learning.md, "The
// rollout check"). Fewer than two folds with rollouts: no check, every correction kept.
OmniRolloutCheck CheckCorrectionsByRollouts(const OmniPredictorInfo& info, const OmniDataset& all,
                                            const std::vector<int>& folds, const std::vector<double>& ridges,
                                            const ResidualCheckInputs& in) {
  const int num_folds = folds.empty() ? 0 : *std::max_element(folds.begin(), folds.end()) + 1;
  const std::vector<FoldStarts> fold_starts = StartsByFold(*in.split, num_folds);  // once for all subsets
  const FoldCost rollouts = [&](int k, const Eigen::VectorXd& scale,
                                const Eigen::MatrixXd& weights) -> std::optional<double> {
    const OmniPredictor p =
        MakeLinearPredictor(info, Eigen::VectorXd::Zero(scale.size()), scale, weights, Eigen::Vector3d::Zero());
    const FoldStarts& f = fold_starts[static_cast<std::size_t>(k)];
    const auto [sum, count] = ResidualRollouts(p, f.part->seq, f.starts, in.frames, in.track);
    if (count == 0) return std::nullopt;
    return sum / static_cast<double>(count);
  };
  const OutputSubsetChoice c = ChooseOutputsByFoldCost(all.x, all.y, folds, ridges, rollouts);
  OmniRolloutCheck check;
  check.chosen = c.chosen;
  check.kept = c.kept;
  check.folds = c.folds;
  check.rmse_chosen = std::sqrt(c.cost_chosen);
  check.rmse_kept = std::sqrt(c.cost_kept);
  check.rmse_none = std::sqrt(c.cost_none);
  return check;
}

// A predictor's weights' own uncertainty (RidgeWeightDirections) from its training rows
// (x: what the weights multiply, y: the targets, in the units the weights predict), in
// blocks of a second of frames (the driving noise's correlation is far shorter): the
// directions holding 95 % of the covariance's trace, at most 16, each drawn once per
// rollout by the learned backend. Only a one-frame predictor drives rollouts.
RidgeWeightUncertainty WeightUncertainty(const OmniPredictorInfo& info, const Eigen::MatrixXd& x,
                                         const Eigen::MatrixXd& y, const Eigen::VectorXd& scale,
                                         const Eigen::MatrixXd& weights, const std::vector<double>& ridges) {
  if (info.layout.horizon != 1) return {};
  const int block_rows = std::max(2, static_cast<int>(std::lround(info.frame_rate)));
  return RidgeWeightDirections(x, y, scale, weights, ridges, block_rows, 0.95, 16);
}

// A residual predictor's ridge regression on scaled inputs, closed form, through the
// origin, fitted on `data`, each output (forward, sideways, turn) with a ridge of
// `ridges` or none chosen by cross-validation over `folds` of `all` by the
// one-standard-error rule: the largest ridge whose mean fold error lies within one
// standard error (over the folds) of the best one's, no correction (ridge infinite)
// counting as the largest. Shrinking a residual's weights moves it toward its physics,
// and a correction's error compounds over the steps that follow, so one that wins a
// frame by less than the folds' scatter is not worth its weights (measured on the
// Robotino: docs/learning.md).
//
// With a track (horizon 1), the corrections so chosen are then checked by what the
// predictor is used for, its rollouts (CheckCorrectionsByRollouts): an output whose
// correction does not make the left-out folds' 1 s rollouts clearly nearer keeps none.
OmniPredictor FitResidualChoosingRidge(const OmniPredictorInfo& info, const OmniDataset& data, const OmniDataset& all,
                                       const std::vector<int>& folds, const std::vector<double>& ridges,
                                       const ResidualCheckInputs& rollouts, ResidualChoice* choice) {
  std::vector<double> r = ChooseRidgesByOneStandardError(all.x, all.y, folds, ridges);
  if (rollouts.track) {
    choice->check = CheckCorrectionsByRollouts(info, all, folds, r, rollouts);
    for (int j = 0; j < 3; ++j)
      if (!(choice->check.kept >> j & 1)) r[static_cast<std::size_t>(j)] = std::numeric_limits<double>::infinity();
  }
  const long n = data.x.cols();
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(3, n);
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(n);
  for (int j = 0; j < 3; ++j) {
    choice->ridge[j] = r[static_cast<std::size_t>(j)];
    if (std::isinf(r[static_cast<std::size_t>(j)])) continue;  // no correction
    weights.row(j) = FitRidge(data.x, data.y.col(j), r[static_cast<std::size_t>(j)], &scale).transpose();  // same scale
  }
  OmniPredictor p = MakeLinearPredictor(info, Eigen::VectorXd::Zero(n), scale, weights, Eigen::Vector3d::Zero());
  p.SetWeightUncertainty(WeightUncertainty(info, data.x, data.y, scale, weights.transpose(), r));
  return p;
}

// Rows of training windows that make a second of log, the block a bootstrap draws whole.
int BlockRows(const OmniPredictorInfo& info) { return std::max(1, static_cast<int>(std::lround(info.frame_rate))); }

// `x` and `y` with `rest` rows of standing still appended (all-zero inputs, no motion):
// what a network learns beside the logs, whose rest holds only under camera noise.
std::pair<Eigen::MatrixXd, Eigen::MatrixXd> WithRestRows(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, long rest) {
  Eigen::MatrixXd xr(x.rows() + rest, x.cols()), yr(y.rows() + rest, y.cols());
  xr << x, Eigen::MatrixXd::Zero(rest, x.cols());
  yr << y, Eigen::MatrixXd::Zero(rest, y.cols());
  return {std::move(xr), std::move(yr)};
}

// `progress` told member `m`'s epochs (0 the first) as its share of the whole ensemble's
// of `members`; empty where `progress` is.
std::function<void(int, int, double)> MemberProgress(const std::function<void(int, int, double)>& progress, int m,
                                                     int members) {
  if (!progress) return {};
  return [&progress, m, members](int epoch, int epochs, double loss) {
    progress(m * epochs + epoch, members * epochs, loss);
  };
}

// Members 1.. of a network's ensemble (OmniTrainOptions::members): each from its own
// start (the seed plus its number) on a block bootstrap of the training windows (blocks
// of `block_rows` drawn with replacement until as many rows; the rest rows added as for
// the first), early-stopped on the same held-out windows. `progress` is told each
// member's epochs as its share of the whole ensemble's, the first member's included.
std::vector<Mlp> TrainEnsembleMembers(const OmniDataset& data, long rest, const OmniDataset& validation,
                                      const OmniTrainOptions& options, int block_rows,
                                      const std::function<void(int, int, double)>& progress) {
  std::vector<Mlp> members;
  const long n = data.rows(), blocks = (n + block_rows - 1) / block_rows;
  for (int m = 1; m < options.members; ++m) {
    MlpOptions o = options.mlp;
    o.seed = options.mlp.seed + static_cast<std::uint64_t>(m);
    Rng rng(o.seed ^ 0x5bd1e995u);
    Eigen::MatrixXd x(n, data.x.cols()), y(n, 3);
    long row = 0;
    while (row < n) {
      const long from = static_cast<long>(rng.Index(static_cast<std::uint64_t>(blocks))) * block_rows;
      const long take = std::min({static_cast<long>(block_rows), n - from, n - row});
      x.middleRows(row, take) = data.x.middleRows(from, take);
      y.middleRows(row, take) = data.y.middleRows(from, take);
      row += take;
    }
    const auto [xr, yr] = WithRestRows(x, y, rest);
    std::string report;
    members.push_back(TrainMlpHoldingOut(xr, yr, validation.x, validation.y, o,
                                         MemberProgress(progress, m, options.members), &report));
  }
  return members;
}

// Fits the predictor on `data`. Linear: ridge regression on scaled inputs, closed form,
// through the origin (all-zero inputs are a robot at rest with zero commands, which must
// stay at rest), a residual one's ridges chosen by FitResidualChoosingRidge (*chosen_ridge;
// zero otherwise). The network early-stops on the held-out one-step windows, placed last;
// standing still (all-zero inputs, no motion) is added to what it learns: real logs hold
// rest only under camera noise.
OmniPredictor FitPredictor(const OmniPredictorInfo& info, const OmniDataset& data, const OmniDataset& validation,
                           const OmniTrainOptions& options, const std::function<void(int, int, double)>& progress,
                           const ResidualCheckInputs& rollouts, std::string* mlp_report, ResidualChoice* choice) {
  const std::vector<SplitLog>& split = *rollouts.split;
  if (options.kind == "linear" && info.layout.residual)
    return FitResidualChoosingRidge(info, data, JoinedWindows(data, validation), RidgeFolds(split),
                                    options.residual_ridges, rollouts, choice);
  if (options.kind == "linear") {
    Eigen::VectorXd scale;
    const Eigen::MatrixXd w = FitRidge(data.x, data.y, options.ridge, &scale);  // in x 3
    OmniPredictor p =
        MakeLinearPredictor(info, Eigen::VectorXd::Zero(w.rows()), scale, w.transpose(), Eigen::Vector3d::Zero());
    p.SetWeightUncertainty(WeightUncertainty(info, data.x, data.y, scale, w, std::vector<double>(3, options.ridge)));
    return p;
  }
  const long rest = std::max<long>(1, data.rows() / 50);
  const auto [x, y] = WithRestRows(data.x, data.y, rest);
  // No weights' uncertainty for a network: its output layer's (the last-layer Laplace
  // approximation) was measured and made held-out rows worse (docs/learning.md). An
  // ensemble instead, where asked for.
  OmniPredictor p =
      MakeMlpPredictor(info, TrainMlpHoldingOut(x, y, validation.x, validation.y, options.mlp,
                                               MemberProgress(progress, 0, options.members), mlp_report));
  p.SetEnsemble(TrainEnsembleMembers(data, rest, validation, options, BlockRows(info), progress));
  return p;
}

// The 1-frame predictor on its own for `rollout_frames` from the held-out windows: the
// RMS position error (m).
double RolloutRmse(const OmniPredictor& predictor, const std::vector<SplitLog>& split, int rollout_frames,
                   NominalOmniTrack* track) {
  double sum = 0;
  long count = 0;
  for (const SplitLog& part : split) {
    auto [s, c] = track ? ResidualRollouts(predictor, part.seq, part.residual_starts, rollout_frames, track)
                        : Rollouts(predictor, part.seq, part.cut, part.seq.frames() - 1, rollout_frames);
    sum += s;
    count += c;
  }
  return count ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

}  // namespace

namespace {

// A residual predictor on both tracks, each trained as if asked for; the one whose
// held-out rollouts come nearer is kept (the tracker where they tie, or where neither
// could roll out). Where one track cannot be trained (its filter diverged, or too few
// windows), the other is kept and the summary says why; where neither can, the tracker's
// error is thrown.
OmniPredictor TrainChoosingNominalState(const OmniModel& model, const std::vector<OmniLog>& logs,
                                        const OmniTrainOptions& options, OmniTrainSummary* summary,
                                        const std::function<void(int, int, double)>& progress) {
  OmniTrainOptions one = options;
  one.choose_nominal_state = false;
  std::optional<OmniPredictor> trained[2];
  OmniTrainSummary summaries[2];
  std::exception_ptr failure[2];
  std::string why[2];
  const OmniReplayState states[2] = {OmniReplayState::kTracker, OmniReplayState::kObserver};
  for (int k = 0; k < 2; ++k) {
    one.nominal_state = states[k];
    try {
      trained[k].emplace(TrainOmniPredictor(model, logs, one, &summaries[k], progress));
    } catch (const std::runtime_error& e) {  // InputError (too few windows) or CheckFailed (its track diverged)
      failure[k] = std::current_exception();
      why[k] = e.what();
    }
  }
  if (!trained[0] && !trained[1]) std::rethrow_exception(failure[0]);
  OmniTrainSummary choice;
  choice.rollout_rmse_tracker = summaries[0].validation_rollout_rmse;
  choice.rollout_rmse_observer = summaries[1].validation_rollout_rmse;
  const int keep = !trained[0] ? 1 : !trained[1] ? 0 : choice.KeepsObserver() ? 1 : 0;
  OmniTrainSummary& kept = summaries[keep];
  kept.rollout_rmse_tracker = choice.rollout_rmse_tracker;
  kept.rollout_rmse_observer = choice.rollout_rmse_observer;
  kept.chosen_state = true;
  kept.kept_state = states[keep];
  if (!trained[1 - keep]) {
    kept.untrained_state = std::string("the ") + OmniReplayStateName(states[1 - keep]) + "'s track could not be trained: " +
                           why[1 - keep];
  }
  kept.seconds = summaries[0].seconds + summaries[1].seconds;
  if (summary) *summary = kept;
  return std::move(*trained[keep]);
}

}  // namespace

OmniPredictor TrainOmniPredictor(const OmniModel& model, const std::vector<OmniLog>& logs,
                                 const OmniTrainOptions& options, OmniTrainSummary* summary,
                                 const std::function<void(int, int, double)>& progress) {
  if (std::string problem; !options.IsValid(&problem)) throw InputError(problem);
  if (logs.empty()) throw InputError("no logs to train on");
  if (options.residual && options.choose_nominal_state) {
    return TrainChoosingNominalState(model, logs, options, summary, progress);
  }
  std::unique_ptr<NominalOmniTrack> track;
  OmniPredictorInfo info = StartInfo(model, logs, options, &track);
  const int rollout_frames = static_cast<int>(std::lround(info.frame_rate));  // 1 s
  OmniDataset train, validation;
  const std::vector<SplitLog> split = SplitLogs(logs, options, rollout_frames, track.get(), &info, &train, &validation);
  info.samples = train.rows() + validation.rows();
  RangesAndBounds(train, split, &info);

  const auto start = std::chrono::steady_clock::now();
  std::string mlp_report;
  ResidualChoice choice;
  const ResidualCheckInputs rollouts{&split, info.layout.horizon == 1 ? track.get() : nullptr, rollout_frames};
  OmniPredictor predictor = FitPredictor(info, train, validation, options, progress, rollouts, &mlp_report, &choice);
  const double rollout = info.layout.horizon == 1 ? RolloutRmse(predictor, split, rollout_frames, track.get()) : 0.0;
  OmniPredictorInfo final_info = info;
  final_info.validation_rollout_rmse = rollout;
  final_info.train_rmse = PositionRmse(PredictAll(predictor, train), train.y);
  final_info.validation_rmse = PositionRmse(PredictAll(predictor, validation), validation.y);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  predictor.info_ = final_info;
  if (summary) {
    summary->samples = info.samples;
    summary->train_samples = train.rows();
    summary->train_rmse = final_info.train_rmse;
    summary->validation_rmse = final_info.validation_rmse;
    summary->seconds = seconds;
    summary->mlp_report = mlp_report;
    summary->validation_rollout_rmse = rollout;
    summary->ridge = choice.ridge;
    summary->rollout_check = choice.check;
    summary->ridge_folds = split.size() >= 2 ? std::to_string(split.size()) + " logs"
                                             : std::to_string(kRidgeStretches) + " stretches of the log";
  }
  return predictor;
}

}  // namespace twinsim
