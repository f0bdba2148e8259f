#include "analysis/omni_calibration.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <unsupported/Eigen/SpecialFunctions>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/covariance_root.h"
#include "core/math_constants.h"
#include "core/pose.h"

namespace twinsim {

namespace {

// A fixed quadrature of the standard bivariate normal: kRadii Rayleigh quantiles times
// kAngles directions (each ring turned by half a step against the last), equal weights.
// Its mean of ||z|| is within 0.3 % of sqrt(pi / 2).
constexpr int kRadii = 16, kAngles = 16;
const std::vector<Eigen::Vector2d>& StandardDraws() {
  static const std::vector<Eigen::Vector2d> draws = [] {
    std::vector<Eigen::Vector2d> z;
    for (int i = 0; i < kRadii; ++i) {
      const double r = std::sqrt(-2 * std::log(1 - (i + 0.5) / kRadii));
      for (int j = 0; j < kAngles; ++j) {
        const double a = (j + 0.5 * (i % 2)) * 2 * kPi / kAngles;
        z.emplace_back(r * std::cos(a), r * std::sin(a));
      }
    }
    return z;
  }();
  return draws;
}

// The energy score of N(0, L L^T) at the outcome y.
double EnergyScore(const Eigen::Matrix2d& root, const Eigen::Vector2d& y) {
  double to_y = 0, spread = 0;
  for (const Eigen::Vector2d& z : StandardDraws()) {
    const Eigen::Vector2d x = root * z;
    to_y += (x - y).norm();
    spread += x.norm();
  }
  const double n = static_cast<double>(StandardDraws().size());
  return to_y / n - std::sqrt(0.5) * spread / n;  // E||X - X'|| = sqrt(2) E||L z||
}

double MeanConstantEnergy(const std::vector<PredictiveError>& rows, double s) {
  double sum = 0;
  const Eigen::Matrix2d root = s * Eigen::Matrix2d::Identity();
  for (const PredictiveError& r : rows) sum += EnergyScore(root, r.e.head<2>());
  return rows.empty() ? 0 : sum / static_cast<double>(rows.size());
}

int PitBin(double u) { return std::clamp(static_cast<int>(u * kPitBins), 0, kPitBins - 1); }

// P(D^2 <= d2) for a position's squared Mahalanobis distance under its covariance:
// chi-square with 2 degrees of freedom for a known covariance (n infinite); with one
// estimated from n draws, F: d2 (n - 1) / (2 n) is F(2, n - 1), whose distribution
// function has this closed form.
double PositionPit(double d2, double n) {
  if (std::isinf(n)) return 1 - std::exp(-0.5 * d2);
  return 1 - std::pow(1 + d2 / n, -0.5 * (n - 1));
}

// Student's t distribution function with nu degrees of freedom (the standard normal's
// for infinitely many), through the regularised incomplete beta function.
double StudentCdf(double t, double nu) {
  if (std::isinf(nu)) return 0.5 * std::erfc(-t / std::sqrt(2.0));
  const double tail = 0.5 * Eigen::numext::betainc(0.5 * nu, 0.5, nu / (nu + t * t));
  return t > 0 ? 1 - tail : tail;
}

}  // namespace

std::vector<PredictiveError> PredictiveErrors(const OmniLog& log, const OmniReplayResult& result,
                                              const std::function<bool(std::size_t)>& keep, int frames) {
  std::vector<PredictiveError> out;
  if (result.covariance.size() != log.rows.size()) return out;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i) || (keep && !keep(i))) continue;
    out.push_back(PredictiveErrorAt(log, result, i));
    if (frames > 0) out.back().turn_rate = MeasuredTurnRate(log, i, frames);
  }
  return out;
}

PredictiveError PredictiveErrorAt(const OmniLog& log, const OmniReplayResult& result, std::size_t i) {
  const Pose2& m = log.rows[i].pose;
  PredictiveError p;
  p.e << m.x - result.pose[i].x, m.y - result.pose[i].y, m.theta - result.pose[i].theta;
  p.c = result.covariance[i] + result.measurement_covariance;
  if (i < result.input_distance.size()) p.input_distance = result.input_distance[i];
  if (result.covariance_draws > 0) {
    p.draws = result.covariance_draws;
    p.drawn = result.covariance[i];
  }
  return p;
}

double EffectiveDraws(const PredictiveError& row, PosePart part) {
  constexpr double kKnown = std::numeric_limits<double>::infinity();
  if (row.draws <= 0) return kKnown;
  double whole = 0, drawn = 0;
  int p = 3;
  if (part == PosePart::kHeading) {
    whole = row.c(2, 2), drawn = row.drawn(2, 2), p = 1;
  } else if (part == PosePart::kPosition) {
    whole = row.c.topLeftCorner<2, 2>().determinant(), drawn = row.drawn.topLeftCorner<2, 2>().determinant(), p = 2;
  } else {
    whole = row.c.determinant(), drawn = row.drawn.determinant();
  }
  // Nothing drawn there (a held row, an axis without noise): the known part alone.
  if (!(drawn > 0) || !(whole > 0)) return kKnown;
  return row.draws * std::pow(whole / drawn, 2.0 / p);
}

Pits PitsOf(const PredictiveError& r) {
  const Eigen::Matrix2d cxy = r.c.topLeftCorner<2, 2>();
  const Eigen::Vector2d exy = r.e.head<2>();
  const double d2 = exy.dot(cxy.ldlt().solve(exy));
  const double z = r.e[2] / std::sqrt(std::max(r.c(2, 2), 1e-300));
  // Chi-square and normal for a known covariance, F and Student's t for one estimated
  // from draws (PredictiveError).
  return {PositionPit(d2, EffectiveDraws(r, PosePart::kPosition)), StudentCdf(z, EffectiveDraws(r, PosePart::kHeading))};
}

double OmniCalibration::EnergyGain() const {
  return baseline_energy_score > 0 ? 1 - energy_score / baseline_energy_score : 0;
}

double ConstantSpread(const std::vector<PredictiveError>& rows) {
  if (rows.empty()) return 0;
  double ms = 0;
  for (const PredictiveError& r : rows) ms += r.e.head<2>().squaredNorm();
  const double rms = std::sqrt(ms / (2.0 * static_cast<double>(rows.size())));
  if (rms <= 0) return 0;
  // Golden-section search on log s over three decades around the per-coordinate RMS.
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double a = std::log(rms) - std::log(100.0), b = std::log(rms) + std::log(10.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = MeanConstantEnergy(rows, std::exp(c)), fd = MeanConstantEnergy(rows, std::exp(d));
  while (b - a > 1e-3) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - g * (b - a);
      fc = MeanConstantEnergy(rows, std::exp(c));
    } else {
      a = c, c = d, fc = fd;
      d = a + g * (b - a);
      fd = MeanConstantEnergy(rows, std::exp(d));
    }
  }
  return std::exp(0.5 * (a + b));
}

OmniCalibration Calibrate(const std::vector<PredictiveError>& rows, double constant_spread) {
  OmniCalibration out;
  out.rows = static_cast<int>(rows.size());
  out.baseline_spread = constant_spread;
  if (rows.empty()) return out;
  int in50 = 0, in90 = 0, h50 = 0, h90 = 0;
  double es = 0, base = 0;
  const Eigen::Matrix2d round = constant_spread * Eigen::Matrix2d::Identity();
  for (const PredictiveError& r : rows) {
    const Eigen::Matrix2d cxy = r.c.topLeftCorner<2, 2>();
    const Eigen::Vector2d exy = r.e.head<2>();
    const Pits pits = PitsOf(r);
    in50 += pits.position <= 0.5;
    in90 += pits.position <= 0.9;
    h50 += std::abs(2 * pits.heading - 1) <= 0.5;
    h90 += std::abs(2 * pits.heading - 1) <= 0.9;
    ++out.position_pit[static_cast<std::size_t>(PitBin(pits.position))];
    ++out.heading_pit[static_cast<std::size_t>(PitBin(pits.heading))];
    es += EnergyScore(CovarianceRoot(cxy), exy);
    base += EnergyScore(round, exy);
  }
  const double n = static_cast<double>(rows.size());
  out.position_50 = in50 / n, out.position_90 = in90 / n;
  out.heading_50 = h50 / n, out.heading_90 = h90 / n;
  out.energy_score = es / n;
  out.baseline_energy_score = base / n;
  out.log_score = MeanLogScore(rows);
  return out;
}

namespace {

// The negative log density of a p-dimensional error whose squared Mahalanobis distance
// under its covariance C is d2 (log |C| = log_det), C known (n infinite) or estimated from
// n draws: then Student's t with nu = n - p + 1 degrees of freedom and scale n C / nu,
// so that e' scale^-1 e / nu = e' C^-1 e / n.
double NegativeLogDensity(double d2, double log_det, int p, double n) {
  if (std::isinf(n) || n <= p) return 0.5 * (d2 + log_det + p * std::log(2 * kPi));
  const double nu = n - p + 1;
  return std::lgamma(0.5 * nu) - std::lgamma(0.5 * (nu + p)) + 0.5 * p * std::log(nu * kPi) +
         0.5 * (log_det + p * std::log(n / nu)) + 0.5 * (nu + p) * std::log1p(d2 / n);
}

}  // namespace

double LogScore(const PredictiveError& r) {
  const Eigen::LLT<Eigen::Matrix3d> llt(0.5 * (r.c + r.c.transpose()));
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d w = llt.matrixL().solve(r.e);
  double log_det = 0;
  for (int i = 0; i < 3; ++i) log_det += 2 * std::log(llt.matrixL()(i, i));
  return NegativeLogDensity(w.squaredNorm(), log_det, 3, EffectiveDraws(r, PosePart::kPose));
}

double PartLogScore(const PredictiveError& r, PosePart part) {
  if (part == PosePart::kPose) return LogScore(r);
  if (part == PosePart::kHeading) {
    const double v = r.c(2, 2);
    if (!(v > 0)) return std::numeric_limits<double>::infinity();
    return NegativeLogDensity(r.e(2) * r.e(2) / v, std::log(v), 1, EffectiveDraws(r, part));
  }
  const Eigen::Matrix2d c = r.c.topLeftCorner<2, 2>();
  const Eigen::LLT<Eigen::Matrix2d> llt(c);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d w = llt.matrixL().solve(r.e.head<2>());
  const double log_det = 2 * (std::log(llt.matrixL()(0, 0)) + std::log(llt.matrixL()(1, 1)));
  return NegativeLogDensity(w.squaredNorm(), log_det, 2, EffectiveDraws(r, part));
}

double MeanLogScore(const std::vector<PredictiveError>& rows) {
  if (rows.empty()) return 0;
  double sum = 0;
  for (const PredictiveError& r : rows) sum += LogScore(r);
  return sum / static_cast<double>(rows.size());
}

double MeasuredTurnRate(const OmniLog& log, std::size_t i, int frames) {
  const int last = log.FrameIndex(i);
  double turned = 0;
  std::size_t j = i;
  for (; j > 0 && log.FrameIndex(j - 1) >= last - frames; --j)
    turned += std::abs(WrapAngle(log.rows[j].pose.theta - log.rows[j - 1].pose.theta));
  const double seconds = log.rows[i].t - log.rows[j].t;
  return seconds > 0 ? turned / seconds : 0;
}

std::vector<std::array<OmniTurnQuarter, 4>> CalibrateRowsByTurnRate(const std::vector<std::vector<PredictiveError>>& rows,
                                                                    const std::vector<int>& horizons, double frame_period) {
  std::vector<std::array<OmniTurnQuarter, 4>> out(horizons.size());
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    std::vector<PredictiveError> sorted = rows[q];
    std::stable_sort(sorted.begin(), sorted.end(),
                     [](const PredictiveError& a, const PredictiveError& b) { return a.turn_rate < b.turn_rate; });
    const std::size_t n = sorted.size();
    for (std::size_t k = 0; k < 4; ++k) {
      const std::vector<PredictiveError> quarter(sorted.begin() + static_cast<std::ptrdiff_t>(k * n / 4),
                                                 sorted.begin() + static_cast<std::ptrdiff_t>((k + 1) * n / 4));
      OmniTurnQuarter& t = out[q][k];
      if (!quarter.empty()) t.from = quarter.front().turn_rate, t.to = quarter.back().turn_rate;
      t.calibration = Calibrate(quarter, ConstantSpread(quarter));
      t.calibration.frames = horizons[q];
      t.calibration.seconds = horizons[q] * frame_period;
    }
  }
  return out;
}

std::vector<std::vector<PredictiveError>> OmniLogPredictiveErrors(
    const OmniModel& model, const OmniLog& log, const std::string& backend, const std::vector<int>& horizons, int stride,
    std::vector<OmniSpreadBudget>* budgets, const std::vector<std::array<OmniModel, 2>>& parameter_shifts) {
  std::vector<std::vector<PredictiveError>> out(horizons.size());
  if (budgets) budgets->clear();
  if (horizons.empty()) return out;
  const int longest = horizons.back();
  if (log.FrameIndex(log.rows.size() - 1) <= longest + kWarmUpFrames) return out;
  OmniReplayOptions o;
  o.backend = backend;
  o.horizon = longest;
  o.also.assign(horizons.begin(), horizons.end() - 1);
  o.covariance = true;
  o.covariance_parts = budgets != nullptr;
  o.stride = stride;
  o.stride_origin = 0;
  o.parameter_shifts = parameter_shifts;
  o.parameter_backend = ReplayEngineFor(model, "", "analytic");
  const OmniReplayResult r = ReplayOmniLog(model, log, o);
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    const OmniReplayResult& at = q + 1 == horizons.size() ? r : r.also[q];
    out[q] = PredictiveErrors(log, at, {}, horizons[q]);
    if (!budgets) continue;
    budgets->push_back(SpreadBudgetOf(log, at, horizons[q]));
    budgets->back().scale = model.observer.IntervalScaleAt(horizons[q])[0];
  }
  return out;
}

std::vector<OmniCalibration> CalibrateRows(const std::vector<std::vector<PredictiveError>>& rows,
                                           const std::vector<int>& horizons, double frame_period, double from,
                                           double to) {
  std::vector<OmniCalibration> out;
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    std::vector<PredictiveError> within;
    for (const PredictiveError& r : rows[q])
      if (r.input_distance >= from && r.input_distance < to) within.push_back(r);
    OmniCalibration c = Calibrate(within, ConstantSpread(within));
    c.frames = horizons[q];
    c.seconds = c.frames * frame_period;
    out.push_back(c);
  }
  return out;
}

std::vector<OmniDistanceCalibration> CalibrateRowsByDistance(const std::vector<std::vector<PredictiveError>>& rows,
                                                             const std::vector<int>& horizons, double frame_period) {
  std::vector<OmniDistanceCalibration> out;
  for (std::size_t b = 0; b + 1 < kCalibrationDistances.size(); ++b) {
    const double from = kCalibrationDistances[b], to = kCalibrationDistances[b + 1];
    out.push_back({from, to, CalibrateRows(rows, horizons, frame_period, from, to)});
  }
  return out;
}

std::vector<OmniCalibration> CalibrateOmniLog(const OmniModel& model, const OmniLog& log, const std::string& backend,
                                              std::vector<int> horizons, int stride) {
  std::sort(horizons.begin(), horizons.end());
  return CalibrateRows(OmniLogPredictiveErrors(model, log, backend, horizons, stride), horizons, log.frame_period);
}

}  // namespace twinsim
