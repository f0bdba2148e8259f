#include "identification_omni/omni_drift_identification.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/clustered_standard_errors.h"
#include "analysis/omni_compare.h"
#include "analysis/omni_replay.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/pattern_search.h"
#include "io/printf_number.h"

namespace twinsim {
namespace {

// The search's coordinates: the logarithms of the forward, sideways and turn spreads and
// of the correlation time.
using DriftValues = std::array<double, 4>;
constexpr double kLowerSpread[3] = {1e-4, 1e-4, 1e-3};  // m/s, m/s, rad/s: below, none to speak of
constexpr double kUpperSpread[3] = {2, 2, 20};
// A drift lasts longer than any prediction a behaviour makes (3 s): a shorter process
// would stand in for the response's own errors, which the fit and the noise's spreads
// answer for.
constexpr double kLowerTime = 3, kUpperTime = 100;  // s
// The drift starts at this share of the fast slip's spreads, lasting this long (s).
constexpr double kStartShare = 0.25;
constexpr double kStartTime = 20;
// The cost (the predictions' mean squared errors as shares of none's) must fall by this much.
constexpr double kLeastGain = 0.05;
constexpr int kBudget = 40;  // evaluations of the predictions' score

OmniDrivingNoise::Drift DriftOf(const DriftValues& v) {
  OmniDrivingNoise::Drift d;
  for (std::size_t a = 0; a < 3; ++a) d.sd[a] = std::exp(v[a]);
  d.correlation_time = std::exp(v[3]);
  return d;
}

// The drift's search clamps its time above ten of the fast slip's too (a slow process,
// not a second fast one).
DriftValues ClampedDrift(DriftValues v, double fast_time) {
  for (std::size_t a = 0; a < 3; ++a) v[a] = std::clamp(v[a], std::log(kLowerSpread[a]), std::log(kUpperSpread[a]));
  v[3] = std::clamp(v[3], std::log(std::max(kLowerTime, 10 * fast_time)), std::log(kUpperTime));
  return v;
}

// The filter's predictions half a second and a second ahead over logs (each replayed on
// its own, in parallel, by its own model with `drift`), from every quarter second after
// the warm-up: the squared position and heading errors summed per horizon, and the rows.
struct AheadErrors {
  std::array<double, 2> sum{0, 0}, heading_sum{0, 0};  // m^2, rad^2
  std::array<int, 2> rows{0, 0};
  // With ErrorsAhead's `with_rows`: each row's errors (x, y m; heading rad), its horizon
  // (0: half a second, 1: a second) and its cluster (kClusterSeconds of a log, numbered
  // from 0 across the logs), logs in order, each log's half-second rows first.
  std::vector<std::array<double, 3>> error;
  std::vector<int> horizon, cluster;
  double Mse(std::size_t h) const { return rows[h] ? sum[h] / rows[h] : std::numeric_limits<double>::infinity(); }
  double HeadingMse(std::size_t h) const {
    return rows[h] ? heading_sum[h] / rows[h] : std::numeric_limits<double>::infinity();
  }
};

// The standard errors' clusters: pieces of a log this long (each of the Robotino's 10 s
// runs one), whose predictions 1 s ahead from every quarter second share their errors.
constexpr double kClusterSeconds = 10;

// Appends the rows of `log` predicted in `r` (one horizon) to *out.
void AppendRows(const OmniLog& log, const OmniReplayResult& r, int horizon, AheadErrors* out) {
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (!PredictedAndMeasured(log, r, i)) continue;
    const Pose2& p = r.pose[i];
    const Pose2& m = log.rows[i].pose;
    out->error.push_back({p.x - m.x, p.y - m.y, WrapAngle(p.theta - m.theta)});
    out->horizon.push_back(horizon);
    out->cluster.push_back(static_cast<int>((log.rows[i].t - log.rows.front().t) / kClusterSeconds));
  }
}

AheadErrors ErrorsAhead(const std::vector<OmniModel>& models, const std::vector<const OmniLog*>& logs,
                        const OmniDrivingNoise::Drift& drift, const OmniNoiseOptions& options, bool with_rows = false) {
  std::vector<AheadErrors> per(logs.size());
  ParallelFor(static_cast<int>(logs.size()), options.threads, [&](int k) {
    const OmniLog& log = *logs[static_cast<std::size_t>(k)];
    OmniModel model = models[static_cast<std::size_t>(k)];
    model.driving_noise.drift = drift;
    const int second = std::max(2, static_cast<int>(std::lround(1 / log.frame_period)));
    OmniReplayOptions o;
    o.backend = options.backend;
    o.horizon = second;
    o.also = {second / 2};
    o.stride = std::max(1, second / 4);
    const OmniReplayResult r = ReplayOmniLog(model, log, o);
    AheadErrors& out = per[static_cast<std::size_t>(k)];
    for (std::size_t h = 0; h < 2; ++h) {
      const CompareErrorRow e = MeasurePredictionErrors(log, h == 0 ? r.also[0] : r);
      out.sum[h] = e.position_rmse * e.position_rmse * e.predicted;
      out.heading_sum[h] = e.heading_rmse * e.heading_rmse * e.predicted;
      out.rows[h] = e.predicted;
      if (with_rows) AppendRows(log, h == 0 ? r.also[0] : r, static_cast<int>(h), &out);
    }
  });
  AheadErrors out;
  int first_cluster = 0;  // each log's pieces numbered after the previous logs'
  for (const AheadErrors& a : per) {
    for (std::size_t h = 0; h < 2; ++h) {
      out.sum[h] += a.sum[h];
      out.heading_sum[h] += a.heading_sum[h];
      out.rows[h] += a.rows[h];
    }
    out.error.insert(out.error.end(), a.error.begin(), a.error.end());
    out.horizon.insert(out.horizon.end(), a.horizon.begin(), a.horizon.end());
    for (int c : a.cluster) out.cluster.push_back(first_cluster + c);
    if (!a.cluster.empty()) first_cluster += *std::max_element(a.cluster.begin(), a.cluster.end()) + 1;
  }
  return out;
}

// The cost's residuals (FitAhead's share, C = the sum of their squares): each row's
// position errors over sqrt(4 N_h MSE0_pos,h), its heading's over sqrt(4 N_h
// MSE0_theta,h), `none` the predictions without a drift.
Eigen::VectorXd Residuals(const AheadErrors& a, const AheadErrors& none) {
  Eigen::VectorXd r(3 * static_cast<Eigen::Index>(a.error.size()));
  for (std::size_t i = 0; i < a.error.size(); ++i) {
    const auto h = static_cast<std::size_t>(a.horizon[i]);
    const double position = std::sqrt(4.0 * none.rows[h] * none.Mse(h));
    const double heading = std::sqrt(4.0 * none.rows[h] * none.HeadingMse(h));
    const auto row = 3 * static_cast<Eigen::Index>(i);
    r[row] = a.error[i][0] / position;
    r[row + 1] = a.error[i][1] / position;
    r[row + 2] = a.error[i][2] / heading;
  }
  return r;
}

// Each coordinate of `fitted` on the search's bound: "lower", "upper" or empty.
std::array<std::string, 4> DriftBounds(const DriftValues& fitted, double fast_time) {
  std::array<std::string, 4> bound;
  for (std::size_t k = 0; k < 4; ++k) {
    DriftValues low = fitted, high = fitted;
    low[k] = -1e300;
    high[k] = 1e300;
    if (fitted[k] <= ClampedDrift(low, fast_time)[k]) bound[k] = "lower";
    if (fitted[k] >= ClampedDrift(high, fast_time)[k]) bound[k] = "upper";
  }
  return bound;
}

// The standard errors (in the values' units) of the fitted drift (coordinates `fitted`):
// the cluster-robust covariance of the cost's residuals (analysis/
// clustered_standard_errors.h), their Jacobian by central differences of 0.1 in the
// logarithms. A coordinate on its bound (`bound`) gets none (NaN); so does every one
// where fewer than two clusters hold rows.
std::array<double, 4> DriftStandardErrors(const std::vector<OmniModel>& models, const std::vector<const OmniLog*>& logs,
                                          const DriftValues& fitted, const std::array<std::string, 4>& bound,
                                          const AheadErrors& none, const OmniNoiseOptions& options, int* evaluations) {
  constexpr double kStep = 0.1;
  std::array<double, 4> se;
  se.fill(std::numeric_limits<double>::quiet_NaN());
  std::vector<int> held;
  for (std::size_t k = 0; k < 4; ++k)
    if (!bound[k].empty()) held.push_back(static_cast<int>(k));
  const AheadErrors at = ErrorsAhead(models, logs, DriftOf(fitted), options, true);
  ++*evaluations;
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(at.error.size()), 4);
  for (std::size_t k = 0; k < 4; ++k) {
    if (!bound[k].empty()) continue;
    DriftValues up = fitted, down = fitted;
    up[k] += kStep;
    down[k] -= kStep;
    const AheadErrors u = ErrorsAhead(models, logs, DriftOf(up), options, true);
    const AheadErrors d = ErrorsAhead(models, logs, DriftOf(down), options, true);
    *evaluations += 2;
    if (u.error.size() != at.error.size() || d.error.size() != at.error.size()) return se;
    jacobian.col(static_cast<Eigen::Index>(k)) = (Residuals(u, none) - Residuals(d, none)) / (2 * kStep);
  }
  std::vector<int> cluster;  // each row's three residuals in its cluster
  for (int c : at.cluster) cluster.insert(cluster.end(), 3, c);
  const std::vector<double> log_se = ClusteredStandardErrors(jacobian, Residuals(at, none), held, cluster);
  if (log_se.size() != 4) return se;
  const OmniDrivingNoise::Drift value = DriftOf(fitted);
  for (std::size_t k = 0; k < 4; ++k)
    se[k] = (k < 3 ? value.sd[k] : value.correlation_time) * log_se[k];  // dv = v d(ln v)
  return se;
}

// The search on the predictions of `logs` by `models` (the drift they carry ignored),
// from a share of the first model's noise: the fit, its mean squared errors against
// none's and, where the gain is too small to matter, the note that says so.
OmniDriftIdentification FitAhead(const std::vector<OmniModel>& models, const std::vector<const OmniLog*>& logs,
                                 const OmniNoiseOptions& options) {
  OmniDriftIdentification out;
  const OmniDrivingNoise& noise = models.front().driving_noise;
  const double fast_time = noise.correlation_time;
  DriftValues start;
  for (std::size_t a = 0; a < 3; ++a) start[a] = std::log(std::max(kStartShare * noise.sd[a], kLowerSpread[a]));
  start[3] = std::log(kStartTime);
  start = ClampedDrift(start, fast_time);
  const AheadErrors none = ErrorsAhead(models, logs, {}, options);
  out.rows = none.rows[0] + none.rows[1];
  bool scorable = true;
  for (std::size_t h = 0; h < 2; ++h) scorable = scorable && none.rows[h] > 0 && none.Mse(h) > 0 && none.HeadingMse(h) > 0;
  if (!scorable) {
    out.note = "the logs hold no prediction a second ahead to fit it on";
    return out;
  }
  out.rmse_before = {std::sqrt(none.Mse(0)), std::sqrt(none.Mse(1))};
  // Each horizon's mean squared error of the position and of the heading as a share of
  // none's, the four averaged.
  const auto share = [&](const AheadErrors& a) {
    double sum = 0;
    for (std::size_t h = 0; h < 2; ++h) sum += a.Mse(h) / none.Mse(h) + a.HeadingMse(h) / none.HeadingMse(h);
    return sum / 4;
  };
  AheadErrors best_errors = none;
  const std::function<double(const DriftValues&)> cost = [&](const DriftValues& v) {
    try {
      const AheadErrors a = ErrorsAhead(models, logs, DriftOf(v), options);
      const double c = share(a);
      if (c < share(best_errors)) best_errors = a;
      return std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
    } catch (const CheckFailed&) {
      return std::numeric_limits<double>::infinity();  // diverged
    }
  };
  double best = cost(start);
  out.evaluations = 2;
  const DriftValues fitted = PatternSearch<DriftValues>(
      cost, [&](DriftValues v) { return ClampedDrift(v, fast_time); }, start, 4, kBudget, &best, &out.evaluations);
  out.drift = DriftOf(fitted);
  out.rmse_after = {std::sqrt(best_errors.Mse(0)), std::sqrt(best_errors.Mse(1))};
  out.bound = DriftBounds(fitted, fast_time);
  if (best <= 1 - kLeastGain) {  // asked for: how well the logs determine it
    try {
      out.standard_error = DriftStandardErrors(models, logs, fitted, out.bound, none, options, &out.evaluations);
    } catch (const CheckFailed&) {
      // a step beside the fit diverged: no errors (NaN), the fit stands
    }
  } else {
    out.note = "the predictions half a second and a second ahead do not ask for one (their mean squared errors " +
               PrintfNumber("%.3g", best) + " of none's; kept from " + PrintfNumber("%.3g", 1 - kLeastGain) + ")";
  }
  return out;
}

}  // namespace

OmniDriftIdentification IdentifyDrift(const OmniModel& given, const std::vector<OmniBlockedStretch>& stretches,
                                      const OmniNoiseOptions& options) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  OmniModel model = given;
  model.driving_noise.drift = {};
  std::vector<const OmniLog*> logs;
  for (const OmniBlockedStretch& s : stretches)
    if (!s.validation && std::find(logs.begin(), logs.end(), s.log) == logs.end()) logs.push_back(s.log);
  if (logs.empty()) throw InputError("the drift needs a fit log");
  OmniDriftIdentification out = FitAhead(std::vector<OmniModel>(logs.size(), model), logs, options);
  out.on = "the fit logs' predictions 0.5 and 1 s ahead";
  if (!out.note.empty()) return out;
  OmniModel with = model;
  with.driving_noise.drift = out.drift;
  out.held_out_before = HeldOutLogScore(model, stretches, options, &out.held_out_rows);
  out.held_out_after = HeldOutLogScore(with, stretches, options);
  if (out.held_out_rows == 0) {
    out.note = "no held-out rows to check it on";
    return out;
  }
  out.kept = out.held_out_after <= out.held_out_before;
  if (!out.kept) {
    out.note = "the held-out blocks' predictions are worse with it (" + PrintfNumber("%.4g", out.held_out_before) + " -> " +
               PrintfNumber("%.4g", out.held_out_after) + " nats per row)";
  }
  return out;
}

OmniDriftIdentification IdentifyDriftOnLeftOutLogs(const std::vector<OmniModel>& models,
                                                   const std::vector<const OmniLog*>& logs,
                                                   const OmniNoiseOptions& options) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  if (models.size() != logs.size() || logs.empty()) throw std::invalid_argument("IdentifyDriftOnLeftOutLogs: a model per log");
  OmniDriftIdentification out = FitAhead(models, logs, options);
  out.on = "the left-out logs' predictions 0.5 and 1 s ahead, each by the model of the others";
  out.kept = out.note.empty();
  return out;
}

}  // namespace twinsim
