#include "identification_omni/omni_noise_identification.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "analysis/held_out_blocks.h"
#include "analysis/omni_replay.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/pattern_search.h"
#include "estimation/omni_observer.h"
#include "io/printf_number.h"

namespace twinsim {

namespace {

// The driving noise's forward, sideways and turn spreads at the logs' typical motion
// (OmniTypicalMotion, which says why there) and correlation time, the scale of the
// model's process noise, the camera's position and heading noise, and the spreads'
// growth with speed, acceleration and turn rate. The search runs in the logarithms of all
// but the growths, which run in log(1 + g), so that they may start at none.
constexpr int kNoiseParams = 10;
constexpr int kPerSpeed = 7, kPerAcceleration = 8, kPerTurnRate = 9;  // the growths, last
constexpr double kLower[kNoiseParams] = {1e-3, 1e-3, 1e-2, 5e-3, 1e-3, OmniObserverModel::kMinMeasurementNoiseXy,
                                         OmniObserverModel::kMinMeasurementNoiseTheta, 0, 0, 0};
constexpr double kUpper[kNoiseParams] = {5, 5, 50, 5, 100, 0.1, 0.5, 20, 20, 20};
constexpr const char* kNames[kNoiseParams] = {"forward",   "sideways",     "turn",      "correlation_time",
                                              "process_noise_scale", "camera_xy", "camera_theta", "per_speed",
                                              "per_acceleration", "per_turn_rate"};
constexpr const char* kUnits[kNoiseParams] = {"m/s", "m/s", "rad/s", "s", "x", "m", "rad", "1/(m/s)", "1/(m/s^2)",
                                              "1/(rad/s)"};
using NoiseValues = std::array<double, kNoiseParams>;  // the search's coordinates

bool IsGrowth(int i) { return i >= kPerSpeed; }
double ToCoordinate(int i, double value) { return IsGrowth(i) ? std::log1p(value) : std::log(value); }
double FromCoordinate(int i, double x) { return IsGrowth(i) ? std::expm1(x) : std::exp(x); }
double Slope(int, double x) { return std::exp(x); }  // d value / d x, for both maps

// The spreads' factor at the typical motion for the growths in `v`.
double GrowthAt(const NoiseValues& v, const OmniTypicalMotion& typical) {
  OmniDrivingNoise n;
  n.per_speed = FromCoordinate(kPerSpeed, v[kPerSpeed]);
  n.per_turn_rate = FromCoordinate(kPerTurnRate, v[kPerTurnRate]);
  return n.Growth(typical.speed, 0, typical.turn_rate);
}

NoiseValues Coordinates(const OmniModel& m, const OmniTypicalMotion& typical) {
  const OmniDrivingNoise& n = m.driving_noise;
  const double growth = n.Growth(typical.speed, 0, typical.turn_rate);
  const double values[kNoiseParams] = {n.sd[0] * growth, n.sd[1] * growth, n.sd[2] * growth, n.correlation_time, 1.0,
                                       m.ObserverNoiseXy(), m.ObserverNoiseTheta(), n.per_speed, n.per_acceleration,
                                       n.per_turn_rate};
  NoiseValues v;
  for (int i = 0; i < kNoiseParams; ++i) v[i] = ToCoordinate(i, values[i]);
  return v;
}

OmniModel WithNoise(OmniModel m, const NoiseValues& v, const OmniTypicalMotion& typical) {
  const double growth = GrowthAt(v, typical);
  for (std::size_t a = 0; a < 3; ++a) m.driving_noise.sd[a] = FromCoordinate(static_cast<int>(a), v[a]) / growth;
  m.driving_noise.correlation_time = FromCoordinate(3, v[3]);
  for (double& q : m.observer.process_noise) q *= FromCoordinate(4, v[4]);
  m.observer.measurement_noise_xy = FromCoordinate(5, v[5]);
  m.observer.measurement_noise_theta = FromCoordinate(6, v[6]);
  m.driving_noise.per_speed = FromCoordinate(kPerSpeed, v[kPerSpeed]);
  m.driving_noise.per_acceleration = FromCoordinate(kPerAcceleration, v[kPerAcceleration]);
  m.driving_noise.per_turn_rate = FromCoordinate(kPerTurnRate, v[kPerTurnRate]);
  return m;
}

NoiseValues Clamped(NoiseValues v) {
  for (int i = 0; i < kNoiseParams; ++i) v[i] = std::clamp(v[i], ToCoordinate(i, kLower[i]), ToCoordinate(i, kUpper[i]));
  return v;
}

// The scored rows of one kind at one horizon: each row's negative log density and block.
struct HorizonRows {
  std::vector<PredictiveError> rows;
  std::vector<int> block;
};

// Which rows Collect gathers: the fit blocks'; the held-out blocks' (never a validation
// log's: they choose); or the rows that report, the validation logs' where there are
// any, else the held-out blocks'. With `blocks`, only rows that start and end in one of
// those blocks.
enum class Rows { kFit, kHeldOutBlocks, kReport };
struct RowSelection {
  Rows rows = Rows::kFit;
  const std::set<int>* blocks = nullptr;  // block numbers; nullptr: every block of the kind
};

// Replays every stretch of the kind once (in parallel) at the longest horizon, the
// others on the way, predicting only from frames the selection scores, and gathers the
// rows per horizon in stretch order.
// With `budgets`, each stretch's spread budget per horizon over the same rows
// (analysis/omni_spread_budget.h) is appended to it.
std::vector<HorizonRows> Collect(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                 const OmniNoiseOptions& options, RowSelection selection,
                                 std::vector<std::vector<OmniSpreadBudget>>* budgets = nullptr) {
  bool any_validation = false;
  for (const OmniBlockedStretch& s : stretches) any_validation = any_validation || s.validation;
  const bool held_out = selection.rows != Rows::kFit;
  const bool validation_only = selection.rows == Rows::kReport && any_validation;
  const int longest = *std::max_element(options.horizons.begin(), options.horizons.end());
  std::vector<std::vector<HorizonRows>> per(stretches.size(), std::vector<HorizonRows>(options.horizons.size()));
  std::vector<std::vector<OmniSpreadBudget>> per_budget(stretches.size());
  ParallelFor(static_cast<int>(stretches.size()), options.threads, [&](int k) {
    const OmniBlockedStretch& s = stretches[static_cast<std::size_t>(k)];
    if (s.validation != validation_only) return;
    auto in_selection = [&](std::size_t row) {
      return row >= s.score_from && static_cast<bool>((*s.held)[row]) == held_out &&
             (!selection.blocks || selection.blocks->count((*s.block)[row]) > 0);
    };
    // The frames in the selection; a prediction from one reaches the longest horizon that
    // ends in one too.
    const int frames = s.log->FrameIndex(s.log->rows.size() - 1) + 1;
    std::vector<char> selected(static_cast<std::size_t>(frames), 0);
    for (std::size_t row = 0; row < s.log->rows.size(); ++row)
      selected[static_cast<std::size_t>(s.log->FrameIndex(row))] = in_selection(row);
    auto is_selected = [&](int frame) { return frame >= 0 && frame < frames && selected[static_cast<std::size_t>(frame)]; };
    if (std::find(selected.begin(), selected.end(), 1) == selected.end()) return;  // nothing to score: not replayed
    OmniReplayOptions o;
    o.backend = options.backend;
    o.horizon = longest;
    o.stride = options.stride;
    o.stride_origin = 0;
    o.reach = [&](int frame) {
      int reach = 0;
      if (!is_selected(frame)) return reach;
      for (int h : options.horizons)
        if (is_selected(frame + h)) reach = std::max(reach, h);
      return reach;
    };
    o.covariance = true;
    o.covariance_parts = budgets != nullptr;
    if (validation_only) o.parameter_shifts = options.parameter_shifts;
    for (int h : options.horizons)
      if (h != longest) o.also.push_back(h);
    const OmniReplayResult r = ReplayOmniLog(model, *s.log, o);
    const int warm = static_cast<int>(std::ceil(options.max_delay / s.log->frame_period)) + kWarmUpFrames;
    for (std::size_t q = 0, a = 0; q < options.horizons.size(); ++q) {
      const int h = options.horizons[q];
      const OmniReplayResult& at = h == longest ? r : r.also[a++];
      HorizonRows& out = per[static_cast<std::size_t>(k)][q];
      // PredictedAndMeasured is SpreadBudgetOf's own test; the rest chooses the rows.
      auto scored = [&](std::size_t row) {
        if (s.log->FrameIndex(row) < warm + h || !ScoredInBlocks(s, row, held_out, h)) return false;
        // With blocks, the prediction ends and starts in them too.
        return !selection.blocks || (in_selection(row) && is_selected(s.log->FrameIndex(row) - h));
      };
      if (budgets) per_budget[static_cast<std::size_t>(k)].push_back(SpreadBudgetOf(*s.log, at, h, scored));
      for (std::size_t row = 0; row < s.log->rows.size(); ++row) {
        if (!PredictedAndMeasured(*s.log, at, row) || !scored(row)) continue;
        out.rows.push_back(PredictiveErrorAt(*s.log, at, row));
        // Only the calibration splits rows by turn rate: the searches' rows go without.
        if (selection.rows == Rows::kReport) out.rows.back().turn_rate = MeasuredTurnRate(*s.log, row, h);
        out.block.push_back((*s.block)[row]);
      }
    }
  });
  if (budgets) {
    for (std::vector<OmniSpreadBudget>& b : per_budget)
      if (!b.empty()) budgets->push_back(std::move(b));
  }
  std::vector<HorizonRows> out(options.horizons.size());
  for (const auto& stretch : per) {
    for (std::size_t q = 0; q < out.size(); ++q) {
      out[q].rows.insert(out[q].rows.end(), stretch[q].rows.begin(), stretch[q].rows.end());
      out[q].block.insert(out[q].block.end(), stretch[q].block.begin(), stretch[q].block.end());
    }
  }
  return out;
}

// The least gain a search's move must bring (PatternSearch's min_gain):
// options.resolution_nats over the average horizon's rows (the cost is a mean per row
// averaged over the horizons: the gain is resolution_nats H / N over N rows on H); 0
// without rows.
double MinGain(const std::vector<HorizonRows>& rows, const OmniNoiseOptions& options) {
  int n = 0, horizons = 0;
  for (const HorizonRows& h : rows) {
    n += static_cast<int>(h.rows.size());
    horizons += !h.rows.empty();
  }
  return n > 0 ? options.resolution_nats * horizons / n : 0;
}

// The cost: the mean negative log density per horizon, averaged over the horizons that
// have rows (each horizon weighs the same, however many rows it has).
double Cost(const std::vector<HorizonRows>& rows) {
  double sum = 0;
  int n = 0;
  for (const HorizonRows& h : rows) {
    if (h.rows.empty()) continue;
    sum += MeanLogScore(h.rows);
    ++n;
  }
  return n ? sum / n : std::numeric_limits<double>::infinity();
}

int CountRows(const std::vector<HorizonRows>& rows) {
  int n = 0;
  for (const HorizonRows& h : rows) n += static_cast<int>(h.rows.size());
  return n;
}

// Each block's share of the cost (its rows' terms of Cost), by block number.
std::map<int, double> BlockTerms(const std::vector<HorizonRows>& rows) {
  std::map<int, double> out;
  int horizons = 0;
  for (const HorizonRows& h : rows) horizons += !h.rows.empty();
  for (const HorizonRows& h : rows) {
    for (std::size_t i = 0; i < h.rows.size(); ++i)
      out[h.block[i]] += LogScore(h.rows[i]) / (static_cast<double>(h.rows.size()) * horizons);
  }
  return out;
}

// Standard errors of the coordinates `free` at `v` (NaN for the others): the sandwich
// H^-1 B H^-1 of the cost, H its Hessian (second differences), B the outer products of
// the blocks' gradients. The trial points are evaluated side by side on options.threads,
// each collecting on one.
NoiseValues StandardErrors(const std::function<std::vector<HorizonRows>(const NoiseValues&, int threads)>& collect,
                           const NoiseValues& v, double cost_at_v, const std::vector<int>& free, int threads,
                           int* evaluations) {
  constexpr double kStep = 0.1;
  NoiseValues se;
  se.fill(std::numeric_limits<double>::quiet_NaN());
  const int n = static_cast<int>(free.size());
  if (n == 0) return se;
  // The trials: each free coordinate up, then down (2i, 2i + 1), then each pair up.
  std::vector<NoiseValues> trials;
  for (int i = 0; i < n; ++i) {
    for (double sign : {1.0, -1.0}) {
      trials.push_back(v);
      trials.back()[free[i]] += sign * kStep;
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      trials.push_back(v);
      trials.back()[free[i]] += kStep;
      trials.back()[free[j]] += kStep;
    }
  }
  std::vector<double> cost(trials.size());
  std::vector<std::map<int, double>> terms(2 * static_cast<std::size_t>(n));
  ParallelFor(static_cast<int>(trials.size()), threads, [&](int t) {
    const std::vector<HorizonRows> rows = collect(trials[static_cast<std::size_t>(t)], 1);
    cost[static_cast<std::size_t>(t)] = Cost(rows);
    if (t < 2 * n) terms[static_cast<std::size_t>(t)] = BlockTerms(rows);
  });
  *evaluations += static_cast<int>(trials.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    h(i, i) = (cost[2 * static_cast<std::size_t>(i)] - 2 * cost_at_v + cost[2 * static_cast<std::size_t>(i) + 1]) /
              (kStep * kStep);
  for (int i = 0, t = 2 * n; i < n; ++i) {
    for (int j = i + 1; j < n; ++j, ++t) {
      h(i, j) = h(j, i) = (cost[static_cast<std::size_t>(t)] - cost[2 * static_cast<std::size_t>(i)] -
                           cost[2 * static_cast<std::size_t>(j)] + cost_at_v) /
                          (kStep * kStep);
    }
  }
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, n);
  for (const auto& [block, unused] : terms[0]) {
    Eigen::VectorXd g(n);
    for (int i = 0; i < n; ++i)
      g[i] = (terms[2 * static_cast<std::size_t>(i)][block] - terms[2 * static_cast<std::size_t>(i) + 1][block]) / (2 * kStep);
    b += g * g.transpose();
  }
  // Where the cost is flat or curved down along some combination (a ridge the search
  // stopped on, e.g. a spread against its growth with speed), the parameters in it are
  // not determined; the others' errors come from the rest (the pseudo-inverse).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(h);
  if (eigen.info() != Eigen::Success) return se;
  const double tolerance = 1e-6 * std::max(eigen.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  Eigen::MatrixXd hi = Eigen::MatrixXd::Zero(n, n);
  std::vector<bool> flat(static_cast<std::size_t>(n), false);
  for (int k = 0; k < n; ++k) {
    const Eigen::VectorXd u = eigen.eigenvectors().col(k);
    if (eigen.eigenvalues()[k] > tolerance) {
      hi += u * u.transpose() / eigen.eigenvalues()[k];
    } else {
      for (int i = 0; i < n; ++i) flat[static_cast<std::size_t>(i)] = flat[static_cast<std::size_t>(i)] || u[i] * u[i] > 0.1;
    }
  }
  const Eigen::MatrixXd cov = hi * b * hi;
  for (int i = 0; i < n; ++i)
    if (!flat[static_cast<std::size_t>(i)]) se[free[i]] = std::sqrt(std::max(0.0, cov(i, i)));
  return se;
}

// The report's parameters: start and identified values (the spreads standing still, as
// the model file has them), errors from the coordinates' (a spread's relative error is
// its error at the typical motion, where it is searched); where `searched`, which sit on
// the search's bounds.
std::vector<OmniNoiseParameter> Parameters(const NoiseValues& start, const NoiseValues& v, const NoiseValues& se,
                                           const OmniTypicalMotion& typical, bool searched = true) {
  std::vector<OmniNoiseParameter> out;
  for (int i = 0; i < kNoiseParams; ++i) {
    const bool spread = i < 3;
    OmniNoiseParameter p;
    p.name = kNames[i];
    p.unit = kUnits[i];
    p.start = FromCoordinate(i, start[i]) / (spread ? GrowthAt(start, typical) : 1);
    p.value = FromCoordinate(i, v[i]) / (spread ? GrowthAt(v, typical) : 1);
    p.standard_error = (spread ? p.value : Slope(i, v[i])) * se[i];  // first order
    if (searched) {
      const double lower = ToCoordinate(i, kLower[i]), upper = ToCoordinate(i, kUpper[i]);
      if (!IsGrowth(i) && v[i] <= lower) p.bound = "lower";
      if (v[i] >= upper) p.bound = "upper";
    }
    out.push_back(p);
  }
  return out;
}

bool Grows(const NoiseValues& v) { return v[kPerSpeed] > 0 || v[kPerAcceleration] > 0 || v[kPerTurnRate] > 0; }

// The noise fitted on some held-out blocks: the same spread at every speed, then with the
// three growths as well, from there (each search within options.max_evaluations).
struct NoiseFit {
  NoiseValues flat{}, grow{};
  double start_cost = 0, flat_cost = 0, grow_cost = 0;  // the cost at the start, after each search
  bool grows() const { return Grows(grow); }
};

// The held-out blocks' rows (those of `blocks` only, where given) with the noise `v`.
std::vector<HorizonRows> CollectHeldOut(const OmniModel& model, const NoiseValues& v, const OmniTypicalMotion& typical,
                                        const std::vector<OmniBlockedStretch>& stretches, const OmniNoiseOptions& options,
                                        const std::set<int>* blocks) {
  try {
    return Collect(WithNoise(model, v, typical), stretches, options, {Rows::kHeldOutBlocks, blocks});
  } catch (const CheckFailed&) {
    return {};  // diverged: no rows, an infinite cost
  }
}

using CollectNoise = std::function<std::vector<HorizonRows>(const NoiseValues&, const std::set<int>*)>;

NoiseFit FitNoise(const CollectNoise& collect, const NoiseValues& start, const std::set<int>* blocks,
                  const OmniNoiseOptions& options, int* evaluations) {
  const std::function<double(const NoiseValues&)> cost = [&](const NoiseValues& x) { return Cost(collect(x, blocks)); };
  NoiseFit f;
  const std::vector<HorizonRows> at_start = collect(start, blocks);
  f.start_cost = f.flat_cost = Cost(at_start);
  const double gain = MinGain(at_start, options);
  ++*evaluations;
  int used = 1;
  f.flat = PatternSearch<NoiseValues>(cost, Clamped, start, kPerSpeed, options.max_evaluations, &f.flat_cost, &used, gain);
  f.grow_cost = f.flat_cost;
  *evaluations += used - 1;
  used = 0;
  f.grow = PatternSearch<NoiseValues>(cost, Clamped, f.flat, kNoiseParams, options.max_evaluations, &f.grow_cost, &used,
                                      gain);
  *evaluations += used;
  return f;
}

// The held-out blocks (of the logs that are not wholly held out) in two halves: every
// other block in time order over all stretches (a log cut into stretches of one or two
// blocks each would otherwise put each stretch's first block in the same half), a block
// that two stretches share counted once.
std::array<std::set<int>, 2> HeldOutHalves(const std::vector<OmniBlockedStretch>& stretches) {
  std::array<std::set<int>, 2> halves;
  std::size_t next = 0;
  for (const OmniBlockedStretch& s : stretches) {
    if (s.validation) continue;
    for (std::size_t row = s.score_from; row < s.log->rows.size(); ++row) {
      const int b = (*s.block)[row];
      if ((*s.held)[row] && halves[0].count(b) == 0 && halves[1].count(b) == 0) halves[next++ % 2].insert(b);
    }
  }
  return halves;
}

// The noise fitted on every held-out block (first) and on each half, side by side (each
// replays its logs in turn).
std::array<NoiseFit, 3> FitAllAndHalves(const OmniModel& model, const OmniTypicalMotion& typical,
                                        const std::vector<OmniBlockedStretch>& stretches,
                                        const OmniNoiseOptions& options, const NoiseValues& start,
                                        const std::array<std::set<int>, 2>& halves, int* evaluations) {
  std::array<NoiseFit, 3> fits;
  std::array<int, 3> used{};
  ParallelFor(3, options.threads, [&](int k) {
    const std::set<int>* blocks = k == 0 ? nullptr : &halves[static_cast<std::size_t>(k - 1)];
    OmniNoiseOptions one = options;
    one.threads = 1;
    const CollectNoise collect = [&](const NoiseValues& v, const std::set<int>* b) {
      return CollectHeldOut(model, v, typical, stretches, one, b);
    };
    fits[static_cast<std::size_t>(k)] = FitNoise(collect, start, blocks, one, &used[static_cast<std::size_t>(k)]);
  });
  for (int u : used) *evaluations += u;
  return fits;
}

// Each half's noise again with the growths held at the whole fit's (fits[0], on every
// held-out block), its spreads, correlation time, process noise and camera refitted from its own
// fit (within half of options.max_evaluations): the noise each half's rows are predicted
// with for the calibration and the intervals' safeguard. A half's own growths, fitted on
// half the rows, decide whether the growths are kept, but they stray far from the whole
// fit's (to the bounds on a minute's log) and judge its intervals by others than its own.
std::array<NoiseValues, 2> HalvesWithTheWholeGrowth(const OmniModel& model, const OmniTypicalMotion& typical,
                                                     const std::vector<OmniBlockedStretch>& stretches,
                                                     const OmniNoiseOptions& options, const std::array<NoiseFit, 3>& fits,
                                                     const std::array<std::set<int>, 2>& halves, int* evaluations) {
  std::array<NoiseValues, 2> out;
  std::array<int, 2> used{};
  ParallelFor(2, options.threads, [&](int k) {
    const std::size_t h = static_cast<std::size_t>(k);
    OmniNoiseOptions one = options;
    one.threads = 1;
    const auto rows = [&](const NoiseValues& x) { return CollectHeldOut(model, x, typical, stretches, one, &halves[h]); };
    const std::function<double(const NoiseValues&)> cost = [&](const NoiseValues& x) { return Cost(rows(x)); };
    NoiseValues start = fits[1 + h].grow;
    for (int i = kPerSpeed; i < kNoiseParams; ++i) start[static_cast<std::size_t>(i)] = fits[0].grow[static_cast<std::size_t>(i)];
    const std::vector<HorizonRows> at_start = rows(start);
    double best = Cost(at_start);
    used[h] = 1;
    out[h] = PatternSearch<NoiseValues>(cost, Clamped, start, kPerSpeed, 1 + options.max_evaluations / 2, &best, &used[h],
                                        MinGain(at_start, options));
  });
  *evaluations += used[0] + used[1];
  return out;
}

// Each half's fits scored on the other half, averaged over the halves: rows that neither
// the response nor the noise was fitted on. `before`, the start's, each half's fit has
// already scored; `grow` is `flat` where a half's growth search found none.
struct CrossedScores {
  double before = 0, flat = 0, grow = 0;
};

CrossedScores ScoreCrossed(const CollectNoise& collect, const std::array<NoiseFit, 3>& fits,
                           const std::array<std::set<int>, 2>& halves, int* evaluations) {
  CrossedScores c;
  for (int k = 0; k < 2; ++k) {
    const std::set<int>* other = &halves[static_cast<std::size_t>(1 - k)];
    const NoiseFit& f = fits[static_cast<std::size_t>(1 + k)];
    const double flat = Cost(collect(f.flat, other));
    c.before += fits[static_cast<std::size_t>(2 - k)].start_cost / 2;  // the other half's fit, at the start
    c.flat += flat / 2;
    c.grow += (f.grows() ? Cost(collect(f.grow, other)) : flat) / 2;
    *evaluations += 1 + f.grows();
  }
  return c;
}

}  // namespace

bool ScoredInBlocks(const OmniBlockedStretch& s, std::size_t i, bool held_out, int horizon) {
  const std::vector<char>& held = *s.held;
  if (i < s.score_from || static_cast<bool>(held[i]) != held_out) return false;
  const int start = s.log->FrameIndex(i) - horizon;
  std::size_t j = i;
  while (j > 0 && s.log->FrameIndex(j) > start) --j;
  return s.log->FrameIndex(j) == start && j >= s.score_from && static_cast<bool>(held[j]) == held_out;
}

bool OmniNoiseOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (horizons.empty()) return fail("the noise needs at least one horizon");
  for (int h : horizons)
    if (h < 1) return fail("a horizon must be 1 frame or more, got " + std::to_string(h));
  if (stride < 1 || score_stride < 1) return fail("strides must be 1 or more");
  if (max_evaluations < 1) return fail("max_evaluations must be 1 or more");
  if (!(resolution_nats >= 0)) return fail("resolution_nats must be 0 or more");
  return true;
}

OmniNoiseIdentification IdentifyDrivingNoise(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                             const OmniNoiseOptions& options) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  OmniNoiseIdentification out;
  out.model = model;
  std::vector<const OmniLog*> logs;
  for (const OmniBlockedStretch& s : stretches)
    if (!s.validation && std::find(logs.begin(), logs.end(), s.log) == logs.end()) logs.push_back(s.log);
  const OmniTypicalMotion typical = TypicalMotionOf(logs);
  const NoiseValues start = Coordinates(model, typical);
  // The noise is fitted on the held-out blocks, rows the response never saw; validation
  // logs only report.
  const CollectNoise collect = [&](const NoiseValues& v, const std::set<int>* blocks) {
    return CollectHeldOut(model, v, typical, stretches, options, blocks);
  };
  const std::vector<HorizonRows> first = collect(start, nullptr);
  out.fit_rows = CountRows(first);
  if (out.fit_rows == 0) {
    out.note = "no held-out rows to fit the noise on: the prediction-error fit's noise is kept";
    NoiseValues none;
    none.fill(std::numeric_limits<double>::quiet_NaN());
    out.parameters = Parameters(start, start, none, typical, false);
    return out;
  }
  out.fit_before = Cost(first);
  int evaluations = 1;
  const std::array<std::set<int>, 2> halves = HeldOutHalves(stretches);
  const std::array<NoiseFit, 3> fits = FitAllAndHalves(model, typical, stretches, options, start, halves, &evaluations);
  const CrossedScores crossed = ScoreCrossed(collect, fits, halves, &evaluations);
  const bool growth = fits[0].grows() && crossed.grow < crossed.flat;
  if (fits[0].grows() && !growth) {
    out.growth_note = "a spread growing with speed (" +
                      PrintfNumber("%.4g", FromCoordinate(kPerSpeed, fits[0].grow[kPerSpeed])) + " per m/s), acceleration (" +
                      PrintfNumber("%.4g", FromCoordinate(kPerAcceleration, fits[0].grow[kPerAcceleration])) +
                      " per m/s^2) and turn rate (" +
                      PrintfNumber("%.4g", FromCoordinate(kPerTurnRate, fits[0].grow[kPerTurnRate])) +
                      " per rad/s) fitted the held-out blocks better, but fitted on each half of them it did not "
                      "score the other half better: none kept";
  }
  const NoiseValues v = growth ? fits[0].grow : fits[0].flat;
  out.fit_after = growth ? fits[0].grow_cost : fits[0].flat_cost;
  std::vector<int> free;
  for (int i = 0; i < kNoiseParams; ++i)
    if (!IsGrowth(i) || v[i] > 0) free.push_back(i);  // no growth: not estimated, no error
  const auto collect_on = [&](const NoiseValues& x, int threads) {
    OmniNoiseOptions o = options;
    o.threads = threads;
    return CollectHeldOut(model, x, typical, stretches, o, nullptr);
  };
  const NoiseValues se = StandardErrors(collect_on, v, out.fit_after, free, options.threads, &evaluations);
  out.evaluations = evaluations;
  out.held_out_rows = out.fit_rows;
  out.held_out_before = crossed.before;
  out.held_out_after = growth ? crossed.grow : crossed.flat;
  out.kept = out.held_out_after < out.held_out_before;
  out.model = WithNoise(model, v, typical);
  out.parameters = Parameters(start, v, se, typical);
  const std::array<NoiseValues, 2> crossed_values =
      growth ? HalvesWithTheWholeGrowth(model, typical, stretches, options, fits, halves, &evaluations)
             : std::array<NoiseValues, 2>{fits[1].flat, fits[2].flat};
  out.evaluations = evaluations;
  for (std::size_t k = 0; k < 2; ++k) {
    out.crossed[k].model = WithNoise(model, crossed_values[k], typical);
    out.crossed[k].blocks = halves[k];
  }
  if (!out.kept) {
    out.model = model;
    out.note = "the noise fitted on each half of the held-out blocks scored the other half worse than the "
               "prediction-error fit's, which is kept";
  }
  return out;
}

double HeldOutLogScore(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                       const OmniNoiseOptions& options, int* rows) {
  std::vector<HorizonRows> held;
  try {
    held = Collect(model, stretches, options, {Rows::kHeldOutBlocks, nullptr});
  } catch (const CheckFailed&) {
    // diverged: no rows, an infinite cost
  }
  if (rows) *rows = CountRows(held);
  return Cost(held);
}

std::vector<OmniCalibration> CalibrateOnBlocks(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                               const OmniNoiseOptions& options,
                                               const std::array<OmniCrossedNoise, 2>* crossed,
                                               std::vector<OmniDistanceCalibration>* by_distance,
                                               std::vector<std::array<OmniTurnQuarter, 4>>* by_turn_rate,
                                               std::vector<OmniSpreadBudget>* budget) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  OmniNoiseOptions scoring = options;
  scoring.stride = options.score_stride;
  bool any_validation = false;
  for (const OmniBlockedStretch& s : stretches) any_validation = any_validation || s.validation;
  const std::vector<HorizonRows> fit = Collect(model, stretches, scoring, {Rows::kFit});
  std::vector<HorizonRows> held;
  // The held-out blocks' budgets, per stretch (and half): none on validation logs.
  std::vector<std::vector<OmniSpreadBudget>> budgets;
  std::vector<std::vector<OmniSpreadBudget>>* on_blocks = budget && !any_validation ? &budgets : nullptr;
  if (crossed && !any_validation) {
    held.resize(options.horizons.size());
    for (int k = 0; k < 2; ++k) {
      const OmniCrossedNoise& other = (*crossed)[static_cast<std::size_t>(1 - k)];
      const std::vector<HorizonRows> half = Collect(
          other.model, stretches, scoring, {Rows::kReport, &(*crossed)[static_cast<std::size_t>(k)].blocks}, on_blocks);
      for (std::size_t q = 0; q < held.size(); ++q)
        held[q].rows.insert(held[q].rows.end(), half[q].rows.begin(), half[q].rows.end());
    }
  } else if (by_distance && any_validation) {
    OmniModel measured = model;  // the same predictions, each with its inputs' distance
    measured.observer.seen_inputs = SeenInputsOfFitBlocks(model, stretches, options);
    held = Collect(measured, stretches, scoring, {Rows::kReport});
  } else {
    held = Collect(model, stretches, scoring, {Rows::kReport}, on_blocks);
  }
  if (budget) *budget = PoolSpreadBudgets(budgets);
  const double period = stretches.empty() ? 0 : stretches.front().log->frame_period;
  std::vector<std::vector<PredictiveError>> rows;
  for (const HorizonRows& h : held) rows.push_back(h.rows);
  if (by_distance && any_validation) *by_distance = CalibrateRowsByDistance(rows, options.horizons, period);
  if (by_turn_rate) *by_turn_rate = CalibrateRowsByTurnRate(rows, options.horizons, period);
  std::vector<OmniCalibration> out;
  for (std::size_t q = 0; q < options.horizons.size(); ++q) {
    OmniCalibration c = Calibrate(held[q].rows, ConstantSpread(fit[q].rows));
    c.frames = options.horizons[q];
    c.seconds = c.frames * period;
    out.push_back(c);
  }
  return out;
}

OmniSeenInputs SeenInputsOfFitBlocks(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                     const OmniNoiseOptions& options) {
  std::vector<std::vector<Eigen::VectorXd>> per(stretches.size());
  ParallelFor(static_cast<int>(stretches.size()), options.threads, [&](int k) {
    const OmniBlockedStretch& s = stretches[static_cast<std::size_t>(k)];
    if (s.validation) return;
    OmniReplayOptions o;
    o.backend = options.backend;
    o.horizon = 1;  // the observer along the log (0 would be the free run), predicting nothing
    o.reach = [](int) { return 0; };
    o.features = true;
    const OmniReplayResult r = ReplayOmniLog(model, *s.log, o);
    for (std::size_t row = s.score_from; row < r.input_feature.size(); ++row)
      if (!(*s.held)[row] && r.input_feature[row].size() > 0) per[static_cast<std::size_t>(k)].push_back(r.input_feature[row]);
  });
  std::vector<Eigen::VectorXd> all;
  for (auto& p : per) all.insert(all.end(), p.begin(), p.end());
  return MakeSeenInputs(all);
}

OmniIntervalSafeguard FitIntervalSafeguard(const OmniModel& given, const std::vector<OmniBlockedStretch>& stretches,
                                           const OmniNoiseOptions& options,
                                           const std::array<OmniCrossedNoise, 2>* crossed) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  auto unscaled = [](OmniModel m) {
    m.observer.interval_scale.clear();
    return m;
  };
  OmniNoiseOptions scoring = options;
  scoring.stride = options.score_stride;
  scoring.horizons = SafeguardHorizons(options.horizons);
  const std::array<std::set<int>, 2> halves =
      crossed ? std::array<std::set<int>, 2>{(*crossed)[0].blocks, (*crossed)[1].blocks} : HeldOutHalves(stretches);
  // rows[horizon][half]
  std::vector<std::vector<std::vector<SafeguardRow>>> rows(scoring.horizons.size(),
                                                           std::vector<std::vector<SafeguardRow>>(2));
  for (std::size_t k = 0; k < 2; ++k) {
    const OmniModel predictor = unscaled(crossed ? (*crossed)[1 - k].model : given);
    const std::vector<HorizonRows> half = Collect(predictor, stretches, scoring, {Rows::kHeldOutBlocks, &halves[k]});
    for (std::size_t q = 0; q < half.size(); ++q) AppendSafeguardRows(half[q].rows, MeasurementCovariance(predictor), &rows[q][k]);
  }
  OmniIntervalSafeguard out = SafeguardFromFolds(scoring.horizons, rows, scoring.stride, kSafeguardLeastRows);
  out.on = "held-out blocks";
  return out;
}

}  // namespace twinsim
