#include "analysis/learned_noise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "analysis/omni_replay.h"
#include "core/error.h"
#include "core/pattern_search.h"
#include "estimation/omni_observer.h"

namespace twinsim {
namespace {

// The search's coordinates: ln of the forward, sideways and turn spreads and of the
// correlation time, then ln(g + kGrowthOffset) of the growths with speed, with
// acceleration and with turn rate (their lower bound is a growth of 0).
using NoiseCoordinates = std::array<double, 7>;
constexpr int kFlat = 4;  // the coordinates of a spread the same at every speed
constexpr int kPerSpeed = 4, kPerAcceleration = 5, kPerTurnRate = 6;
constexpr double kGrowthOffset = 0.05;
// The bounds of the coordinates' values: the spreads at the typical motion (m/s, m/s,
// rad/s), the correlation time (s), the growths (1/(m/s), 1/(m/s^2), 1/(rad/s)).
constexpr NoiseCoordinates kLower{1e-3, 1e-3, 1e-3, 0.01, 0, 0, 0};
constexpr NoiseCoordinates kUpper{3, 3, 20, 5, 20, 20, 20};

double ToCoordinate(std::size_t i, double value) {
  value = std::clamp(value, kLower[i], kUpper[i]);
  return std::log(i < kFlat ? value : value + kGrowthOffset);
}

// The spreads' coordinates are those at the logs' typical motion (OmniTypicalMotion; with the
// spreads standing still as coordinates the search stopped at no growth where the
// rollouts were a third too wide at low speed).
NoiseCoordinates ToCoordinates(const OmniDrivingNoise& n, const OmniTypicalMotion& typical) {
  NoiseCoordinates v;
  for (std::size_t a = 0; a < 3; ++a) v[a] = ToCoordinate(a, n.sd[a] * n.Growth(typical.speed, 0, typical.turn_rate));
  v[3] = ToCoordinate(3, n.correlation_time);
  v[kPerSpeed] = ToCoordinate(kPerSpeed, n.per_speed);
  v[kPerAcceleration] = ToCoordinate(kPerAcceleration, n.per_acceleration);
  v[kPerTurnRate] = ToCoordinate(kPerTurnRate, n.per_turn_rate);
  return v;
}

OmniDrivingNoise FromCoordinates(const NoiseCoordinates& v, const OmniTypicalMotion& typical) {
  OmniDrivingNoise n;
  n.correlation_time = std::exp(v[3]);
  // At the lower bound a growth is 0, not the rounding left of exp(ln 0.05) - 0.05.
  auto growth = [](double c) { return c <= std::log(kGrowthOffset) + 1e-12 ? 0.0 : std::exp(c) - kGrowthOffset; };
  n.per_speed = growth(v[kPerSpeed]);
  n.per_acceleration = growth(v[kPerAcceleration]);
  n.per_turn_rate = growth(v[kPerTurnRate]);
  for (std::size_t a = 0; a < 3; ++a) n.sd[a] = std::exp(v[a]) / n.Growth(typical.speed, 0, typical.turn_rate);
  n.simulated = true;
  return n;
}

NoiseCoordinates Clamp(NoiseCoordinates v) {
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::clamp(v[i], ToCoordinate(i, kLower[i]), ToCoordinate(i, kUpper[i]));
  return v;
}

// The predicted rows of each of `logs` at each horizon (sorted; rows[log][horizon], in
// time order), `predictor` drawing `noise` (with its safeguard's scales, if it has any);
// *stride_used (if given) is the frames between starts.
std::vector<std::vector<std::vector<PredictiveError>>> SampledRowsByLog(const OmniModel& model,
                                                                        const OmniPredictor& predictor,
                                                                        const OmniDrivingNoise& noise,
                                                                        const std::vector<OmniLog>& logs,
                                                                        const LearnedNoiseOptions& options,
                                                                        std::vector<int> horizons,
                                                                        int* stride_used = nullptr) {
  auto with_noise = std::make_shared<OmniPredictor>(predictor);
  with_noise->SetDrivingNoise(noise);
  // Every stride-th frame after the warm-up, the stride grown to keep to max_starts.
  long frames = 0;
  for (const OmniLog& log : logs)
    if (log.rows.size() >= 2) frames += std::max(0, log.FrameIndex(log.rows.size() - 1) - horizons.back() - kWarmUpFrames);
  const int stride = std::max<long>(options.stride, (frames + options.max_starts - 1) / std::max(1, options.max_starts));
  if (stride_used) *stride_used = stride;
  std::vector<std::vector<std::vector<PredictiveError>>> by_log(
      logs.size(), std::vector<std::vector<PredictiveError>>(horizons.size()));
  for (std::size_t l = 0; l < logs.size(); ++l) {
    const OmniLog& log = logs[l];
    if (log.rows.size() < 2 || log.FrameIndex(log.rows.size() - 1) <= horizons.back() + kWarmUpFrames) continue;
    OmniReplayOptions o;
    o.backend = "learned";
    o.backend_options.predictor = with_noise;
    o.horizon = horizons.back();
    o.also.assign(horizons.begin(), horizons.end() - 1);
    o.samples = options.samples;
    o.parameter_draws = options.parameter_draws;
    o.seed = options.seed + 0x9e3779b97f4a7c15ULL * l;  // each log draws its own
    o.stride = stride;
    const OmniReplayResult r = ReplayOmniLog(model, log, o);
    for (std::size_t q = 0; q < horizons.size(); ++q)
      by_log[l][q] = PredictiveErrors(log, q + 1 == horizons.size() ? r : r.also[q], {}, horizons[q]);
  }
  return by_log;
}

// The same, every log's rows pooled per horizon.
std::vector<std::vector<PredictiveError>> SampledRows(const OmniModel& model, const OmniPredictor& predictor,
                                                      const OmniDrivingNoise& noise, const std::vector<OmniLog>& logs,
                                                      const LearnedNoiseOptions& options, const std::vector<int>& horizons) {
  std::vector<std::vector<PredictiveError>> rows(horizons.size());
  for (auto& log : SampledRowsByLog(model, predictor, noise, logs, options, horizons))
    for (std::size_t q = 0; q < horizons.size(); ++q) rows[q].insert(rows[q].end(), log[q].begin(), log[q].end());
  return rows;
}

// `predictor` without a safeguard: the rollouts as drawn, for the fits.
OmniPredictor Unscaled(OmniPredictor predictor) {
  predictor.SetIntervalScale({});
  return predictor;
}

double MeanCost(const std::vector<std::vector<PredictiveError>>& rows) {
  double sum = 0;
  for (const auto& h : rows) sum += MeanLogScore(h);
  return sum / static_cast<double>(rows.size());
}

std::vector<int> Sorted(std::vector<int> horizons) {
  std::sort(horizons.begin(), horizons.end());
  horizons.erase(std::unique(horizons.begin(), horizons.end()), horizons.end());
  if (horizons.empty() || horizons.front() < 1) throw InputError("the noise's horizons must be 1 frame or more");
  return horizons;
}

std::vector<OmniCalibration> CalibrationOf(const std::vector<std::vector<PredictiveError>>& rows,
                                           const std::vector<int>& horizons, double frame_period) {
  std::vector<OmniCalibration> out;
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    OmniCalibration c = Calibrate(rows[q], ConstantSpread(rows[q]));
    c.frames = horizons[q];
    c.seconds = c.frames * frame_period;
    out.push_back(c);
  }
  return out;
}

}  // namespace

bool LongEnoughForLearnedNoise(const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options) {
  const int longest = Sorted(options.horizons).back();
  for (const OmniLog& log : logs)
    if (log.rows.size() >= 2 && log.FrameIndex(log.rows.size() - 1) > longest + kWarmUpFrames) return true;
  return false;
}

LearnedNoiseFit FitLearnedDrivingNoise(const OmniModel& model, const OmniPredictor& predictor,
                                       const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options,
                                       const std::function<void(int, int)>& progress) {
  if (predictor.info().layout.horizon != 1)
    throw InputError("a driving noise is fitted for a predictor of one frame ahead, not " +
                     std::to_string(predictor.info().layout.horizon));
  const std::vector<int> horizons = Sorted(options.horizons);
  const OmniPredictor unscaled = Unscaled(predictor);
  LearnedNoiseFit out;
  out.start = LearnedDrivingNoise(model, &unscaled);
  const int budget = 1 + options.max_evaluations + options.max_evaluations / 2;
  std::vector<const OmniLog*> pointers;
  for (const OmniLog& log : logs) pointers.push_back(&log);
  const OmniTypicalMotion typical = TypicalMotionOf(pointers);
  auto rows_at = [&](const NoiseCoordinates& v) {
    return SampledRows(model, unscaled, FromCoordinates(v, typical), logs, options, horizons);
  };
  std::function<double(const NoiseCoordinates&)> cost = [&](const NoiseCoordinates& v) {
    if (progress) progress(out.evaluations, budget);
    return MeanCost(rows_at(v));
  };
  const NoiseCoordinates start = ToCoordinates(out.start, typical);
  const std::vector<std::vector<PredictiveError>> first = rows_at(start);
  for (const auto& h : first) out.rows += static_cast<int>(h.size());
  if (first.back().empty()) {
    throw InputError("the held-out rows give no prediction " + std::to_string(horizons.back()) +
                     " frames ahead to fit the learned backend's driving noise on (a longer log, or a larger validation share)");
  }
  out.cost_before = MeanCost(first);
  out.evaluations = 1;
  double best = out.cost_before;
  // First the same spread at every speed, then the growths about the typical motion.
  NoiseCoordinates v =
      PatternSearch<NoiseCoordinates>(cost, Clamp, start, kFlat, 1 + options.max_evaluations, &best, &out.evaluations);
  v = PatternSearch<NoiseCoordinates>(cost, Clamp, v, kFlat, kPerTurnRate + 1, budget, &best, &out.evaluations);
  out.cost_after = best;
  out.noise = FromCoordinates(v, typical);
  out.calibration = CalibrationOf(rows_at(v), horizons, logs.front().frame_period);
  if (progress) progress(budget, budget);
  return out;
}

OmniIntervalSafeguard FitLearnedIntervalSafeguard(const OmniModel& model, const OmniPredictor& predictor,
                                                  const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options) {
  const OmniPredictor unscaled = Unscaled(predictor);
  const std::vector<int> horizons = SafeguardHorizons(Sorted(options.horizons));
  // Fresh draws: the noise's search chose its spreads under its own draws (common random
  // numbers), which would flatter it here.
  LearnedNoiseOptions fresh = options;
  fresh.seed = options.seed + 0x5afe;
  int stride = options.stride;
  const auto by_log = SampledRowsByLog(model, unscaled, LearnedDrivingNoise(model, &unscaled), logs, fresh,
                                       horizons, &stride);
  // rows[horizon][fold]: alternate logs where each fold so gets enough rows at every
  // horizon (the folds further apart in time), else each log's earlier and later starts.
  const bool by_logs = [&] {
    std::vector<std::array<std::size_t, 2>> count(horizons.size(), std::array<std::size_t, 2>{});
    std::size_t fold = 0;
    for (const auto& log : by_log) {
      if (log.back().empty()) continue;
      for (std::size_t q = 0; q < horizons.size(); ++q) count[q][fold % 2] += log[q].size();
      ++fold;
    }
    return std::all_of(count.begin(), count.end(), [](const std::array<std::size_t, 2>& c) {
      return std::min(c[0], c[1]) >= static_cast<std::size_t>(kSafeguardLeastRows);
    });
  }();
  const Eigen::Matrix3d camera = MeasurementCovariance(model);
  std::vector<std::vector<std::vector<SafeguardRow>>> rows(horizons.size(), std::vector<std::vector<SafeguardRow>>(2));
  std::size_t fold = 0;
  for (const auto& log : by_log) {
    if (log.back().empty()) continue;
    for (std::size_t q = 0; q < horizons.size(); ++q) {
      if (by_logs) {
        AppendSafeguardRows(log[q], camera, &rows[q][fold % 2]);
        continue;
      }
      const auto middle = log[q].begin() + static_cast<std::ptrdiff_t>(log[q].size() / 2);
      AppendSafeguardRows({log[q].begin(), middle}, camera, &rows[q][0]);
      AppendSafeguardRows({middle, log[q].end()}, camera, &rows[q][1]);
    }
    ++fold;
  }
  OmniIntervalSafeguard out = SafeguardFromFolds(horizons, rows, stride, kSafeguardLeastRows);
  out.on = by_logs ? "held-out rows, alternate logs as folds" : "held-out rows, each log's halves as folds";
  return out;
}

std::vector<OmniCalibration> CalibrateLearnedOmniLog(const OmniModel& model, const OmniPredictor& predictor,
                                                     const OmniLog& log, const LearnedNoiseOptions& options,
                                                     std::vector<std::array<OmniTurnQuarter, 4>>* by_turn_rate,
                                                     std::vector<OmniDistanceCalibration>* by_distance) {
  const std::vector<int> horizons = Sorted(options.horizons);
  const OmniDrivingNoise& noise = LearnedDrivingNoise(model, &predictor);
  LearnedNoiseOptions every = options;  // a calibration scores every stride-th frame
  every.max_starts = std::numeric_limits<int>::max();
  const std::vector<std::vector<PredictiveError>> rows = SampledRows(model, predictor, noise, {log}, every, horizons);
  if (by_turn_rate) *by_turn_rate = CalibrateRowsByTurnRate(rows, horizons, log.frame_period);
  if (by_distance && !predictor.info().input_low.empty())
    *by_distance = CalibrateRowsByDistance(rows, horizons, log.frame_period);
  return CalibrationOf(rows, horizons, log.frame_period);
}

std::string FormatLearnedNoiseFit(const LearnedNoiseFit& fit) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line,
                "driving noise: forward %.3g m/s, sideways %.3g m/s, turn %.3g rad/s standing, growing by %.3g per m/s, "
                "%.3g per m/s^2 and %.3g per rad/s, correlation time %.3g s (%d evaluations; %.3f -> %.3f nats per row)\n",
                fit.noise.sd[0], fit.noise.sd[1], fit.noise.sd[2], fit.noise.per_speed, fit.noise.per_acceleration,
                fit.noise.per_turn_rate, fit.noise.correlation_time, fit.evaluations, fit.cost_before, fit.cost_after);
  s << line;
  for (const OmniCalibration& c : fit.calibration) {
    std::snprintf(line, sizeof line,
                  "  %2d frames (%.2f s, %d rows): 50 %% ellipse %.1f %%, 90 %% ellipse %.1f %%, energy score %.4g m "
                  "(constant spread %.4g m)\n",
                  c.frames, c.seconds, c.rows, 100 * c.position_50, 100 * c.position_90, c.energy_score,
                  c.baseline_energy_score);
    s << line;
  }
  return s.str();
}

}  // namespace twinsim
