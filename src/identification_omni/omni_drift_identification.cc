#include "identification_omni/omni_drift_identification.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

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
  double Mse(std::size_t h) const { return rows[h] ? sum[h] / rows[h] : std::numeric_limits<double>::infinity(); }
  double HeadingMse(std::size_t h) const {
    return rows[h] ? heading_sum[h] / rows[h] : std::numeric_limits<double>::infinity();
  }
};

AheadErrors ErrorsAhead(const std::vector<OmniModel>& models, const std::vector<const OmniLog*>& logs,
                        const OmniDrivingNoise::Drift& drift, const OmniNoiseOptions& options) {
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
    }
  });
  AheadErrors out;
  for (const AheadErrors& a : per) {
    for (std::size_t h = 0; h < 2; ++h) {
      out.sum[h] += a.sum[h];
      out.heading_sum[h] += a.heading_sum[h];
      out.rows[h] += a.rows[h];
    }
  }
  return out;
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
  if (!(best <= 1 - kLeastGain)) {
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
