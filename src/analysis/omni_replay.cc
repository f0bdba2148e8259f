#include "analysis/omni_replay.h"

#include <cmath>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>

#include "backends/omni_backend_factory.h"
#include "core/covariance_root.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "learning/omni_predictor.h"
#include "robots/omni/omni_driving_noise.h"

namespace twinsim {

bool OmniReplayOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (horizon < 0) return fail("--horizon must be 0 or more, got " + std::to_string(horizon));
  if (stride < 1) return fail("stride must be 1 or more, got " + std::to_string(stride));
  if (samples < 0) return fail("--samples must be 0 or more, got " + std::to_string(samples));
  if (samples > 0 && horizon < 1) return fail("--samples draws predictions K >= 1 frames ahead (--horizon 1 or more)");
  if (covariance_parts && !covariance) return fail("a covariance's parts come with the covariance");
  if ((covariance || !also.empty()) && horizon < 1)
    return fail("a prediction's covariance and shorter horizons come from predictions K >= 1 frames ahead");
  for (int h : also)
    if (h < 1 || h >= horizon) return fail("a shorter horizon must lie in 1.." + std::to_string(horizon - 1) + ", got " + std::to_string(h));
  return observer.IsValid(why);
}

bool OmniReplayOptions::OnStride(int frame, int since_warm_up) const {
  const int counted = stride_origin >= 0 ? frame - stride_origin : since_warm_up;
  return ((counted % stride) + stride) % stride == 0;
}

int OmniReplayResult::num_predicted() const {
  int n = 0;
  for (bool p : predicted) n += p;
  return n;
}

double PositionRmse(const OmniLog& log, const OmniReplayResult& result) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < result.t.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i)) continue;
    sum += std::pow(result.pose[i].x - log.rows[i].pose.x, 2) + std::pow(result.pose[i].y - log.rows[i].pose.y, 2);
    ++n;
  }
  return n ? std::sqrt(sum / n) : 0.0;
}

OmniPoseErrors PoseErrorsInRobotFrame(const OmniLog& log, const OmniReplayResult& result, double radius) {
  OmniPoseErrors out;
  for (std::size_t i = 0; i < result.pose.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i)) continue;
    const Pose2& m = log.rows[i].pose;
    const double dx = m.x - result.pose[i].x, dy = m.y - result.pose[i].y;
    const double c = std::cos(m.theta), s = std::sin(m.theta);
    out.rows.push_back(i);
    out.e.push_back({c * dx + s * dy, -s * dx + c * dy, radius * (m.theta - result.pose[i].theta)});
  }
  return out;
}

namespace {

// N draws of a pose from a Gaussian of `mean` and covariance `c` (x, y, theta) into *out:
// mean + L z with L L^T = c (core/covariance_root.h).
void DrawSamples(const Pose2& mean, const Eigen::Matrix3d& c, int n, Rng* rng, std::vector<Pose2>* out) {
  const Eigen::Matrix3d root = CovarianceRoot(c);
  out->resize(static_cast<std::size_t>(n));
  for (Pose2& p : *out) {
    const Eigen::Vector3d z(rng->Gaussian(1.0), rng->Gaussian(1.0), rng->Gaussian(1.0));
    const Eigen::Vector3d d = root * z;
    p = Pose2{mean.x + d[0], mean.y + d[1], mean.theta + d[2]};
  }
}

// One frame into the filter; a divergence names the log row at or before the frame.
void AddFrameAt(OmniObserver* observer, const OmniLog& log, const std::map<int, std::size_t>& row_of_frame, int f,
                const std::optional<Pose2>& camera, const Twist2& command) {
  try {
    observer->AddFrame(camera, command);
  } catch (const CheckFailed& e) {
    auto at = row_of_frame.upper_bound(f);
    const std::size_t row = at == row_of_frame.begin() ? 0 : std::prev(at)->second;
    throw CheckFailed(log.path + ":" + std::to_string(log.line_of[row]) + ": " + e.what());
  }
}

// Row `at` of *result from frame j (1..K) of `prediction`, its heading moved by `shift`
// onto the log's branch, with its covariance where the result keeps them, the
// parameters' part (`parameter_parts`' row `at`, where given) added to it.
void PutPrediction(const OmniPrediction& prediction, int j, std::size_t at, double shift,
                   const std::function<void(std::size_t, const Pose2&)>& check,
                   const std::vector<Eigen::Matrix3d>* parameter_parts, OmniReplayResult* result) {
  Pose2 p = prediction.pose[static_cast<std::size_t>(j - 1)];
  check(at, p);
  p.theta += shift;
  result->pose[at] = p;
  result->predicted[at] = true;
  if (!result->covariance.empty()) result->covariance[at] = prediction.pose_covariance[static_cast<std::size_t>(j - 1)];
  if (!result->covariance_parts.empty())
    result->covariance_parts[at] = prediction.pose_covariance_parts[static_cast<std::size_t>(j - 1)];
  if (!prediction.input_distance.empty()) {
    result->input_distance.resize(result->pose.size(), 0.0);
    result->input_distance[at] = prediction.input_distance[static_cast<std::size_t>(j - 1)];
  }
  if (parameter_parts && !result->parameter_covariance.empty()) {
    result->parameter_covariance[at] = (*parameter_parts)[at];
    result->covariance[at] += (*parameter_parts)[at];
  }
}

// The shift that puts a prediction's headings on the log's unwrapped branch at `row`.
double UnwrapShift(const OmniLog& log, std::size_t row, const OmniObserver& observer) {
  const double d = log.rows[row].pose.theta - observer.Estimate().pose.theta;
  return d - WrapAngle(d);
}

// Row `row`'s input as the observer saw it and its estimated body velocity
// (OmniReplayOptions::features), once started.
void RecordInput(const OmniObserver& observer, std::size_t row, OmniReplayResult* out) {
  if (!observer.started()) return;
  out->input_feature.resize(out->pose.size());
  out->estimated_velocity.resize(out->pose.size());
  out->input_feature[row] = observer.InputFeature();
  out->estimated_velocity[row] = observer.Estimate().velocity;
}

// The last frame the observer's replay filters: with `reach` (and no `features` to
// record), the last frame `reach` names (a prediction starts there or earlier, each
// running the model on by itself). A filter that would diverge only after it goes
// unseen: its predictions are the same.
int LastFrameToFilter(const OmniReplayOptions& options, int last_frame) {
  if (!options.reach || options.features) return last_frame;
  int f = last_frame;
  while (f >= 0 && options.reach(f) <= 0) --f;
  return f;
}

// The observer's replay (OmniReplayOptions::state kObserver): the filter runs along the
// log; each prediction (or the stretch's free run) starts from its estimate. `parameter
// parts`: per horizon (K, then `also`'s) each row's parameters' part, or null.
void ObserverReplay(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                    const std::function<void(int, int)>& progress, std::size_t stretch_first, std::size_t stretch_last,
                    const std::map<int, std::size_t>& row_of_frame, const std::vector<Twist2>& command_at,
                    const std::function<void(std::size_t, const Pose2&)>& check, std::unique_ptr<OmniBackend> backend,
                    const std::vector<std::vector<Eigen::Matrix3d>>* parameter_parts, OmniReplayResult* out) {
  OmniObserver observer(model, std::move(backend), options.observer);
  auto parts_of = [&](std::size_t h) { return parameter_parts ? &(*parameter_parts)[h] : nullptr; };
  const int k = options.horizon;
  const bool with_covariance = options.covariance || options.samples > 0;
  Rng draws = Rng::Derived(options.seed, 0x73616d70);  // "samp": the samples' own stream
  const int last_frame = static_cast<int>(command_at.size()) - 1;
  const bool stretch = stretch_first < stretch_last;
  auto planned = [&](int f, int until) {
    return std::vector<Twist2>(command_at.begin() + std::min(f + 1, last_frame + 1),
                               command_at.begin() + std::min(until, last_frame) + 1);
  };
  const int filter_until = stretch ? last_frame : LastFrameToFilter(options, last_frame);
  int start_frame = -1;
  for (int f = 0; f <= filter_until; ++f) {
    if (progress && f % 64 == 0) progress(f, last_frame);
    auto here = row_of_frame.find(f);
    std::optional<Pose2> camera;
    if (here != row_of_frame.end() && log.rows[here->second].measured) camera = log.rows[here->second].pose;
    AddFrameAt(&observer, log, row_of_frame, f, camera, command_at[static_cast<std::size_t>(f)]);
    if (observer.started() && start_frame < 0) start_frame = f;
    if (here == row_of_frame.end()) continue;
    const std::size_t row = here->second;
    if (options.features) RecordInput(observer, row, out);
    if (stretch && row == stretch_first) {
      if (!observer.started() || f - start_frame < kWarmUpFrames) {
        throw InputError(log.path + ":" + std::to_string(log.line_of[stretch_first]) +
                         ": a free run must start after the observer's warm-up of " + std::to_string(kWarmUpFrames) +
                         " frames");
      }
      // The free run: no more corrections from the measurement.
      const int end_frame = log.FrameIndex(stretch_last - 1);
      const double shift = UnwrapShift(log, row, observer);
      const OmniPrediction run = observer.PredictAhead(end_frame - f, planned(f, end_frame));
      for (int j = 1; j <= end_frame - f; ++j) {
        auto it = row_of_frame.find(f + j);
        if (it == row_of_frame.end()) continue;
        Pose2 p = run.pose[static_cast<std::size_t>(j - 1)];
        check(it->second, p);
        p.theta += shift;
        out->pose[it->second] = p;
        out->predicted[it->second] = true;
      }
      out->grip = observer.backend().grip();
      return;
    }
    if (!observer.started()) continue;
    const int since = f - start_frame - kWarmUpFrames;
    if (stretch || since < 0 || !options.OnStride(f, since)) continue;
    const int reach = options.reach ? std::min(k, options.reach(f)) : k;
    if (reach <= 0) continue;
    // The rows this start predicts: K frames on, and each shorter horizon's (within reach).
    auto target = reach == k ? row_of_frame.find(f + k) : row_of_frame.end();
    bool any = target != row_of_frame.end();
    for (int h : options.also) any = any || (h <= reach && row_of_frame.count(f + h) > 0);
    if (!any) continue;
    const OmniPrediction prediction =
        observer.PredictAhead(reach, planned(f, f + reach), with_covariance, options.covariance_parts);
    const double shift = UnwrapShift(log, row, observer);
    for (std::size_t a = 0; a < options.also.size(); ++a) {
      if (options.also[a] > reach) continue;
      auto at = row_of_frame.find(f + options.also[a]);
      if (at != row_of_frame.end())
        PutPrediction(prediction, options.also[a], at->second, shift, check, parts_of(a + 1), &out->also[a]);
    }
    if (target == row_of_frame.end()) continue;
    PutPrediction(prediction, k, target->second, shift, check, parts_of(0), out);
    if (options.samples > 0)
      DrawSamples(out->pose[target->second], out->covariance[target->second], options.samples, &draws,
                  &out->samples[target->second]);
  }
  out->measurement_covariance = observer.measurement_covariance();
  for (OmniReplayResult& a : out->also) a.measurement_covariance = out->measurement_covariance;
  if (progress) progress(last_frame, last_frame);
  out->grip = observer.backend().grip();
}

// Sizes a replay's result in `state` for what `options` ask: per row the samples, the
// covariances (with `covariance`), and a result of the same shape per shorter horizon
// (its camera covariance the result's).
void SizeResult(const OmniLog& log, const OmniReplayOptions& options, const std::string& state, bool covariance,
                OmniReplayResult* out) {
  const std::size_t n = log.rows.size();
  out->state = state;
  if (options.samples > 0) out->samples.resize(n);
  OmniCovarianceParts none;
  none.fill(Eigen::Matrix3d::Zero());
  if (covariance) out->covariance.assign(n, Eigen::Matrix3d::Zero());
  if (options.covariance_parts) out->covariance_parts.assign(n, none);
  for (std::size_t a = 0; a < options.also.size(); ++a) {
    out->also.push_back(HeldMeasurements(log));
    out->also.back().delay_frames = out->delay_frames;
    out->also.back().state = state;
    out->also.back().measurement_covariance = out->measurement_covariance;
    if (covariance) out->also.back().covariance.assign(n, Eigen::Matrix3d::Zero());
    if (options.covariance_parts) out->also.back().covariance_parts.assign(n, none);
  }
}

// Rows not predicted hold their measured pose in every one of the `samples` samples.
void HoldUnpredictedSamples(int samples, OmniReplayResult* out) {
  for (std::size_t i = 0; i < out->samples.size(); ++i)
    if (out->samples[i].empty()) out->samples[i].assign(static_cast<std::size_t>(samples), out->pose[i]);
}

// ReplayOmniLog, or with stretch_first < stretch_last the free run of ReplayOmniStretch.
// The log's frames: the row of each frame, and the command in force at each frame (held
// over lost frames), `delay` frames late.
struct Timeline {
  std::map<int, std::size_t> row_of_frame;
  std::vector<Twist2> command_at;
  int last_frame = 0;
  int delay = 0;  // frames, command and vision
  Twist2 Delayed(int frame) const {
    return frame - delay < 0 ? Twist2{} : command_at[static_cast<std::size_t>(frame - delay)];
  }
};

Timeline MakeTimeline(const OmniLog& log, int delay) {
  Timeline tl;
  tl.delay = delay;
  const std::size_t n = log.rows.size();
  for (std::size_t i = 0; i < n; ++i) tl.row_of_frame[log.FrameIndex(i)] = i;
  tl.last_frame = log.FrameIndex(n - 1);
  tl.command_at = log.CommandAtEveryFrame();
  return tl;
}

using PoseCheck = std::function<void(std::size_t, const Pose2&)>;

// A learned prediction's distance from its training inputs (OmniBackend::TakeInputExcess)
// as row `row`'s input_distance.
void SetInputDistance(std::size_t row, double excess, OmniReplayResult* out) {
  out->input_distance.resize(out->pose.size(), 0.0);
  out->input_distance[row] = excess;
}

// Steps the backend freely from frame `from` to frame `to`, each pose at a logged frame
// stored (theta kept on the log's unwrapped branch from `theta`).
void FreeRun(OmniBackend& backend, const Timeline& tl, int from, int to, double theta, const PoseCheck& check,
             const std::function<void(int, int)>& progress, OmniReplayResult* out) {
  for (int f = from; f < to; ++f) {
    backend.StepFrame({tl.Delayed(f)});
    auto it = tl.row_of_frame.find(f + 1);
    if (it != tl.row_of_frame.end()) {
      Pose2 p = backend.pose(0);
      check(it->second, p);
      p.theta = theta = theta + WrapAngle(p.theta - theta);
      out->pose[it->second] = p;
      out->predicted[it->second] = true;
    }
    if (progress && f % 64 == 0) progress(f + 1, tl.last_frame);
  }
}

// The backend's pose as the prediction of log row `row`, checked, its heading on the
// log's unwrapped branch at `from` (rad).
Pose2 PredictedPose(const OmniBackend& backend, std::size_t row, double from, const PoseCheck& check) {
  Pose2 p = backend.pose(0);
  check(row, p);
  p.theta = from + WrapAngle(p.theta - from);
  return p;
}

// The tracker's sampled predictions (OmniReplayOptions::samples): from each start, N
// rollouts of the backend K frames ahead, each moved on by a driving noise drawn from the
// samples' own stream (SlipPose, the slip starting at rest: the measured window already
// holds the motion so far). Each predicted row gets its N poses, and it and each shorter
// horizon's row the draws' covariance about the prediction without the noise. With a
// safeguard's `scales` (a learned predictor's interval_scale), each horizon's draws are
// spread about the prediction by its scales (position, heading), and so is their
// covariance.
class TrackerSamples {
 public:
  TrackerSamples(const OmniDrivingNoise& noise, std::vector<OmniObserverModel::IntervalScale> scales,
                 const OmniReplayOptions& options, double dt)
      : noise_(noise), scales_(std::move(scales)), options_(options), dt_(dt),
        rng_(Rng::Derived(options.seed, 0x73616d70)) {}

  void Draw(OmniBackend& backend, const OmniBackendState& saved, const Timeline& tl, int f, double from,
            const PoseCheck& check, OmniReplayResult* out) {
    const int k = options_.horizon, n = options_.samples;
    // Per horizon (the also ones, then K): the rows and their draws.
    std::vector<int> horizons = options_.also;
    horizons.push_back(k);
    std::vector<std::vector<Pose2>> draws(horizons.size());
    for (int m = 0; m < n; ++m) {
      backend.Restore(saved);
      if (options_.parameter_draws) backend.DrawParameters(&rng_);
      std::array<double, 3> slip{};
      for (int j = f; j < f + k; ++j) {
        const Twist2 before = backend.velocity(0);
        backend.StepFrame({tl.Delayed(j)});
        backend.PushBody(0, SlipPose(noise_, dt_, backend.velocity(0), before, backend.pose(0), &slip, &rng_));
        for (std::size_t h = 0; h < horizons.size(); ++h) {
          if (j + 1 != f + horizons[h]) continue;
          auto at = tl.row_of_frame.find(j + 1);
          if (at == tl.row_of_frame.end()) continue;
          draws[h].push_back(PredictedPose(backend, at->second, from, check));
        }
      }
    }
    if (options_.parameter_draws) backend.DrawParameters(nullptr);  // the estimate again
    for (std::size_t h = 0; h < horizons.size(); ++h) {
      if (draws[h].empty()) continue;
      OmniReplayResult& r = h + 1 == horizons.size() ? *out : out->also[h];
      const std::size_t row = tl.row_of_frame.at(f + horizons[h]);
      const Pose2& mean = r.pose[row];
      Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
      const std::array<double, 2> scale = IntervalScaleAt(scales_, horizons[h]);
      const bool scaled = scale[0] != 1 || scale[1] != 1;
      for (Pose2& p : draws[h]) {
        Eigen::Vector3d d(p.x - mean.x, p.y - mean.y, WrapAngle(p.theta - mean.theta));
        if (scaled) {
          d = Eigen::Vector3d(scale[0], scale[0], scale[1]).asDiagonal() * d;
          p = Pose2{mean.x + d.x(), mean.y + d.y(), mean.theta + d.z()};
        }
        c += d * d.transpose();
      }
      r.covariance[row] = c / static_cast<double>(draws[h].size());
      r.covariance_draws = static_cast<int>(draws[h].size());
      if (h + 1 == horizons.size()) out->samples[row] = std::move(draws[h]);
    }
  }

 private:
  OmniDrivingNoise noise_;
  std::vector<OmniObserverModel::IntervalScale> scales_;
  const OmniReplayOptions& options_;
  double dt_;
  Rng rng_;
};

// The open-loop tracker: the backend moved to every measured pose, and from each frame on
// the stride a K-frame prediction; or, with a stretch, a free run from its first row
// (after the tracker's warm-up).
// With `samples`, each prediction's sampled rollouts too; and the shorter horizons
// (OmniReplayOptions::also) from the same rollouts.
void TrackerReplay(OmniBackend& backend, const OmniLog& log, const OmniReplayOptions& options, const Timeline& tl,
                   const PoseCheck& check, const std::function<void(int, int)>& progress, std::size_t stretch_first,
                   std::size_t stretch_last, TrackerSamples* samples, OmniReplayResult* out) {
  const int k = options.horizon;
  const bool stretch = stretch_first < stretch_last;
  // The tracker starts at the first row at or after frame D that has a row before it.
  auto first = tl.row_of_frame.lower_bound(std::max(tl.delay, log.FrameIndex(1)));
  if (first == tl.row_of_frame.end()) return;
  const std::size_t r0 = first->second;
  const OmniLogRow& prev = log.rows[r0 - 1];
  const OmniLogRow& now = log.rows[r0];
  const double dt = now.t - prev.t;
  const Twist2 field_v{(now.pose.x - prev.pose.x) / dt, (now.pose.y - prev.pose.y) / dt,
                       (now.pose.theta - prev.pose.theta) / dt};
  backend.Reset(0, now.pose, FieldToBody(field_v, now.pose.theta));

  if (stretch && log.FrameIndex(stretch_first) - first->first < kWarmUpFrames) {
    throw InputError(log.path + ":" + std::to_string(log.line_of[stretch_first]) +
                     ": a free run must start after the tracker's warm-up of " + std::to_string(kWarmUpFrames) +
                     " frames");
  }
  for (int f = first->first; f <= tl.last_frame; ++f) {
    if (progress && f % 64 == 0) progress(f, tl.last_frame);
    auto measured = tl.row_of_frame.find(f);
    // Frames without a new measurement leave the tracker to its own prediction.
    if (measured != tl.row_of_frame.end() && log.rows[measured->second].measured) {
      backend.MoveBody(0, log.rows[measured->second].pose);
    }
    if (stretch && measured != tl.row_of_frame.end() && measured->second == stretch_first) {
      // The free run: no more corrections from the measurement.
      FreeRun(backend, tl, f, log.FrameIndex(stretch_last - 1), log.rows[stretch_first].pose.theta, check, {}, out);
      return;
    }
    auto target = tl.row_of_frame.find(f + k);
    const int since = f - first->first - kWarmUpFrames;
    if (!stretch && measured != tl.row_of_frame.end() && target != tl.row_of_frame.end() && since >= 0 &&
        options.OnStride(f, since) && (!options.reach || options.reach(f) > 0)) {
      const OmniBackendState saved = backend.Save();
      // Keep theta on the log's unwrapped branch.
      const double from = log.rows[measured->second].pose.theta;
      // A learned backend's inputs: how far beyond its training the prediction went. The
      // count starts again here: the tracking steps and the previous prediction's sampled
      // rollouts since the last take are not this prediction's.
      double excess = backend.TakeInputExcess() >= 0 ? 0 : -1;
      for (int j = f; j < f + k; ++j) {
        backend.StepFrame({tl.Delayed(j)});
        if (excess >= 0) excess = std::max(excess, backend.TakeInputExcess());
        for (std::size_t a = 0; a < options.also.size(); ++a) {
          if (j + 1 != f + options.also[a]) continue;
          auto at = tl.row_of_frame.find(j + 1);
          if (at == tl.row_of_frame.end()) continue;
          out->also[a].pose[at->second] = PredictedPose(backend, at->second, from, check);
          out->also[a].predicted[at->second] = true;
          if (excess >= 0) SetInputDistance(at->second, excess, &out->also[a]);
        }
      }
      out->pose[target->second] = PredictedPose(backend, target->second, from, check);
      out->predicted[target->second] = true;
      if (excess >= 0) SetInputDistance(target->second, excess, out);
      if (samples) samples->Draw(backend, saved, tl, f, from, check, out);
      backend.Restore(saved);
    }
    if (f < tl.last_frame) backend.StepFrame({tl.Delayed(f)});
  }
  if (progress) progress(static_cast<int>(log.rows.size()), static_cast<int>(log.rows.size()));
}

OmniReplayResult Replay(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                        const std::function<void(int, int)>& progress, std::size_t stretch_first,
                        std::size_t stretch_last);

// The parameters' part of each predicted row's covariance, per horizon (K, then
// `also`'s): the shifted models' predictions (OmniReplayOptions::parameter_shifts, each
// replayed on its own thread, the mean only), sum_l d_l d_l^T with d_l half the
// difference of pair l's (the heading's wrapped).
std::vector<std::vector<Eigen::Matrix3d>> ParameterParts(const OmniLog& log, const OmniReplayOptions& options) {
  OmniReplayOptions mean = options;
  mean.samples = 0;
  mean.covariance = mean.covariance_parts = mean.features = false;
  mean.parameter_shifts.clear();
  if (!options.parameter_backend.empty()) mean.backend = options.parameter_backend;
  const int n = 2 * static_cast<int>(options.parameter_shifts.size());
  std::vector<OmniReplayResult> runs(static_cast<std::size_t>(n));
  ParallelFor(n, 0, [&](int i) {
    runs[static_cast<std::size_t>(i)] =
        Replay(options.parameter_shifts[static_cast<std::size_t>(i / 2)][static_cast<std::size_t>(i % 2)], log, mean, {}, 0, 0);
  });
  std::vector<std::vector<Eigen::Matrix3d>> out(1 + options.also.size(),
                                                std::vector<Eigen::Matrix3d>(log.rows.size(), Eigen::Matrix3d::Zero()));
  for (std::size_t h = 0; h < out.size(); ++h) {
    for (int l = 0; l < n / 2; ++l) {
      const OmniReplayResult& plus = h == 0 ? runs[2 * l] : runs[2 * l].also[h - 1];
      const OmniReplayResult& minus = h == 0 ? runs[2 * l + 1] : runs[2 * l + 1].also[h - 1];
      for (std::size_t i = 0; i < log.rows.size(); ++i) {
        if (!plus.predicted[i] || !minus.predicted[i]) continue;
        const Eigen::Vector3d d(0.5 * (plus.pose[i].x - minus.pose[i].x), 0.5 * (plus.pose[i].y - minus.pose[i].y),
                                0.5 * WrapAngle(plus.pose[i].theta - minus.pose[i].theta));
        out[h][i] += d * d.transpose();
      }
    }
  }
  return out;
}

OmniReplayResult Replay(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                        const std::function<void(int, int)>& progress, std::size_t stretch_first,
                        std::size_t stretch_last) {
  if (std::string problem; !options.IsValid(&problem)) throw InputError(problem);

  FrameTiming timing;
  timing.frame_rate = 1.0 / log.frame_period;
  timing.physics_substeps = DefaultPhysicsSubsteps(timing.frame_rate);
  FieldModel field;
  field.walls = false;  // a log's robot may be anywhere; walls are not part of a replay
  std::unique_ptr<OmniBackend> backend = MakeOmniBackend(options.backend, {model}, field, timing, options.backend_options);

  const int delay = model.command_delay_frames + model.vision_delay_frames;
  const Timeline tl = MakeTimeline(log, delay);
  const PoseCheck check = [&](std::size_t row, const Pose2& p) {
    if (!IsFinite(p)) {
      std::ostringstream msg;
      msg << log.path << ":" << log.line_of[row] << ": model " << model.name << " on " << options.backend
          << " diverged while predicting t = " << log.rows[row].t << " s";
      throw CheckFailed(msg.str());
    }
  };

  OmniReplayResult out = HeldMeasurements(log);
  out.delay_frames = delay;

  if (options.horizon == 0) {
    out.state = "none";
    // One free run from the first row; its velocity from the first two rows.
    const OmniLogRow& a = log.rows[0];
    const OmniLogRow& b = log.rows[1];
    const double dt = b.t - a.t;
    const Twist2 field_v{(b.pose.x - a.pose.x) / dt, (b.pose.y - a.pose.y) / dt, (b.pose.theta - a.pose.theta) / dt};
    backend->Reset(0, a.pose, FieldToBody(field_v, a.pose.theta));
    FreeRun(*backend, tl, 0, tl.last_frame, a.pose.theta, check, progress, &out);
    out.grip = backend->grip();
    return out;
  }

  if (options.state == OmniReplayState::kObserver && backend->has_velocity_state()) {
    const bool covariance = options.covariance || options.samples > 0;
    SizeResult(log, options, OmniReplayStateName(OmniReplayState::kObserver), covariance, &out);
    std::vector<std::vector<Eigen::Matrix3d>> parts;
    if (covariance && !options.parameter_shifts.empty() && stretch_first >= stretch_last) {
      parts = ParameterParts(log, options);
      out.parameter_covariance.assign(log.rows.size(), Eigen::Matrix3d::Zero());
      for (OmniReplayResult& a : out.also) a.parameter_covariance = out.parameter_covariance;
    }
    ObserverReplay(model, log, options, progress, stretch_first, stretch_last, tl.row_of_frame, tl.command_at, check,
                   std::move(backend), parts.empty() ? nullptr : &parts, &out);
    HoldUnpredictedSamples(options.samples, &out);
    return out;
  }
  if (options.covariance && options.samples == 0)
    throw InputError("a prediction's covariance needs the observer's state (analytic, ode or bullet) or samples (--samples N) on " +
                     options.backend);
  std::optional<TrackerSamples> samples;
  if (options.samples > 0) {
    // The predictor's own noise where it has one (LearnedDrivingNoise), with its safeguard.
    const OmniPredictor* predictor = options.backend_options.predictor.get();
    samples.emplace(LearnedDrivingNoise(model, predictor),
                    predictor && predictor->info().has_driving_noise ? predictor->info().interval_scale
                                                                      : std::vector<OmniObserverModel::IntervalScale>{},
                    options, 1.0 / timing.frame_rate);
    out.measurement_covariance = MeasurementCovariance(model);
  }
  SizeResult(log, options, OmniReplayStateName(OmniReplayState::kTracker), options.samples > 0, &out);
  TrackerReplay(*backend, log, options, tl, check, progress, stretch_first, stretch_last, samples ? &*samples : nullptr, &out);
  HoldUnpredictedSamples(options.samples, &out);
  out.bounded_steps = backend->bounded_steps();
  out.unseen_input_steps = backend->unseen_input_steps();
  out.grip = backend->grip();
  return out;
}

}  // namespace

OmniReplayResult HeldMeasurements(const OmniLog& log) {
  OmniReplayResult out;
  const std::size_t n = log.rows.size();
  out.t.resize(n);
  out.pose.resize(n);
  out.predicted.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    out.t[i] = log.rows[i].t;
    out.pose[i] = log.rows[i].pose;
  }
  return out;
}

OmniReplayResult ReplayOmniLog(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                               const std::function<void(int, int)>& progress) {
  return Replay(model, log, options, progress, 0, 0);
}

OmniReplayResult ReplayOmniStretch(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                                   std::size_t first_row, std::size_t last_row) {
  if (!(first_row < last_row && last_row <= log.rows.size())) {
    throw InputError(log.path + ": rows [" + std::to_string(first_row) + ", " + std::to_string(last_row) +
                     ") are not a stretch of the log's " + std::to_string(log.rows.size()) + " rows");
  }
  OmniReplayOptions o = options;
  o.horizon = std::max(o.horizon, 1);  // the tracker's mode
  return Replay(model, log, o, {}, first_row, last_row);
}

}  // namespace twinsim
