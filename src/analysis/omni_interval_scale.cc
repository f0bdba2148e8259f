#include "analysis/omni_interval_scale.h"

#include <Eigen/Dense>
#include <unsupported/Eigen/SpecialFunctions>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "core/math_constants.h"
#include "io/printf_number.h"

namespace twinsim {
namespace {

// The squared standardised error of `part` with the prediction's covariance scaled by s,
// and the log determinant of that covariance (for the density).
struct Standardised {
  double d2 = 0, log_det = 0;
  int dims = 0;
};

Standardised StandardisedError(const SafeguardRow& row, PosePart part, double s) {
  const Eigen::Matrix3d& predicted = row.predicted;
  const Eigen::Matrix3d& camera = row.camera;
  if (part == PosePart::kHeading) {
    const double v = s * s * predicted(2, 2) + camera(2, 2);
    return {row.e(2) * row.e(2) / v, std::log(v), 1};
  }
  const Eigen::Matrix2d c = s * s * predicted.topLeftCorner<2, 2>() + camera.topLeftCorner<2, 2>();
  const Eigen::Vector2d e = row.e.head<2>();
  const Eigen::LDLT<Eigen::Matrix2d> ldlt(c);
  return {e.dot(ldlt.solve(e)), std::log(c.determinant()), 2};
}

// The chi-square quantile of `dims` (1 or 2) degrees of freedom at probability p: for
// one, the square of the normal's (1 + p) / 2 quantile.
double ChiSquareQuantile(int dims, double p) {
  if (dims == 2) return -2 * std::log(1 - p);
  const double z = Eigen::numext::ndtri(0.5 * (1 + p));
  return z * z;
}

// The row with its prediction's covariance scaled by s, as calibration scores it.
PredictiveError ScaledRow(const SafeguardRow& row, double s) {
  PredictiveError p;
  p.e = row.e;
  p.drawn = s * s * row.predicted;
  p.c = p.drawn + row.camera;
  p.draws = row.draws;
  return p;
}

// Whether the central `level` region of `part` holds the row with its prediction's
// covariance scaled by s: d^2 <= q (the chi-square quantile of `level`) for a known
// covariance; the Student t's region (its PIT within `level`) for one from draws.
bool Holds(const SafeguardRow& row, PosePart part, double s, double level, double q) {
  if (row.draws <= 0) return !(StandardisedError(row, part, s).d2 > q);
  const Pits pits = PitsOf(ScaledRow(row, s));
  return part == PosePart::kHeading ? std::abs(2 * pits.heading - 1) <= level : pits.position <= level;
}

// The smallest s in [0, most] whose central `level` region (q its chi-square quantile)
// holds the row (the region grows with s); infinity where `most` does not.
double SmallestHoldingScale(const SafeguardRow& row, PosePart part, double most, double level, double q) {
  auto outside = [&](double s) { return !Holds(row, part, s, level, q); };
  if (!outside(0)) return 0;
  if (outside(most)) return std::numeric_limits<double>::infinity();
  double lo = 0, hi = most;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (outside(mid) ? lo : hi) = mid;
  }
  return hi;
}

// The ceil((n + 1) level)-th smallest of the n scores (at most the largest): the split
// conformal quantile.
double ConformalRank(std::vector<double> scores, double level) {
  const std::size_t n = scores.size();
  const std::size_t k = std::min(n, static_cast<std::size_t>(std::ceil((static_cast<double>(n) + 1) * level)));
  std::nth_element(scores.begin(), scores.begin() + static_cast<long>(k - 1), scores.end());
  return scores[k - 1];
}

}  // namespace

void AppendSafeguardRows(const std::vector<PredictiveError>& rows, const Eigen::Matrix3d& camera,
                         std::vector<SafeguardRow>* out) {
  for (const PredictiveError& r : rows) out->push_back({r.e, r.c - camera, camera, r.input_distance, r.draws});
}

double ConformalIntervalScale(const std::vector<SafeguardRow>& rows, PosePart part, double most, double level) {
  if (rows.empty()) return 1;
  const int dims = part == PosePart::kHeading ? 1 : 2;
  const double q = ChiSquareQuantile(dims, level);
  // Each row's score: the smallest s in [0, most] that holds it (d^2 falls as s grows).
  std::vector<double> scores;
  scores.reserve(rows.size());
  for (const SafeguardRow& row : rows) scores.push_back(SmallestHoldingScale(row, part, most, level, q));
  return std::clamp(ConformalRank(std::move(scores), level), 1 / most, most);
}

double ConformalIntervalGrowth(const std::vector<SafeguardRow>& rows, PosePart part, double base, double level) {
  constexpr double kMost = OmniObserverModel::kMaxIntervalGrowth;
  if (rows.empty()) return 0;
  // Each row's score: the smallest g whose base (1 + g d) holds it, from the smallest
  // scale that holds it (at most base (1 + kMost d): beyond, infinite).
  const double q = ChiSquareQuantile(part == PosePart::kHeading ? 1 : 2, level);
  std::vector<double> scores;
  scores.reserve(rows.size());
  for (const SafeguardRow& row : rows) {
    const double d = std::max(row.distance, kMinGrowthDistance);
    const double needed = SmallestHoldingScale(row, part, base * (1 + kMost * d), level, q);
    scores.push_back(std::isfinite(needed) ? std::max(0.0, (needed / base - 1) / d) : needed);
  }
  return std::clamp(ConformalRank(std::move(scores), level), 0.0, kMost);
}

ScaledIntervals ScoreIntervalScale(const std::vector<SafeguardRow>& rows, PosePart part, double scale, double growth) {
  ScaledIntervals out;
  const int dims = part == PosePart::kHeading ? 1 : 2;
  const double q50 = ChiSquareQuantile(dims, 0.5), q90 = ChiSquareQuantile(dims, 0.9);
  for (const SafeguardRow& row : rows) {
    const double s = scale * (1 + growth * row.distance);
    if (row.draws > 0) {
      out.inside_50 += Holds(row, part, s, 0.5, q50);
      out.inside_90 += Holds(row, part, s, 0.9, q90);
      out.log_score += PartLogScore(ScaledRow(row, s), part);
    } else {
      const Standardised z = StandardisedError(row, part, s);
      out.inside_50 += z.d2 <= q50;
      out.inside_90 += z.d2 <= q90;
      out.log_score += 0.5 * (z.d2 + z.log_det + dims * std::log(2 * kPi));
    }
    ++out.rows;
  }
  if (out.rows > 0) {
    out.inside_50 /= out.rows;
    out.inside_90 /= out.rows;
    out.log_score /= out.rows;
  }
  return out;
}

ScaledIntervals Pooled(const ScaledIntervals& a, const ScaledIntervals& b) {
  ScaledIntervals out;
  out.rows = a.rows + b.rows;
  if (out.rows == 0) return out;
  auto mean = [&](double x, double y) { return (a.rows * x + b.rows * y) / out.rows; };
  out.inside_50 = mean(a.inside_50, b.inside_50);
  out.inside_90 = mean(a.inside_90, b.inside_90);
  out.log_score = mean(a.log_score, b.log_score);
  return out;
}

bool OmniIntervalSafeguard::AnyKept() const {
  return std::any_of(horizons.begin(), horizons.end(),
                     [](const OmniSafeguardHorizon& h) { return h.position_kept || h.heading_kept; });
}

std::vector<OmniObserverModel::IntervalScale> OmniIntervalSafeguard::Scales() const {
  std::vector<OmniObserverModel::IntervalScale> out;
  const bool any = std::any_of(horizons.begin(), horizons.end(), [](const OmniSafeguardHorizon& h) {
    return h.position != 1 || h.heading != 1 || h.position_growth > 0 || h.heading_growth > 0;
  });
  if (!any) return out;
  for (const OmniSafeguardHorizon& h : horizons)
    out.push_back({h.frames, h.position, h.heading, h.position_growth, h.heading_growth});
  return out;
}

std::vector<int> SafeguardHorizons(std::vector<int> horizons) {
  std::sort(horizons.begin(), horizons.end());
  horizons.erase(std::unique(horizons.begin(), horizons.end()), horizons.end());
  std::vector<int> out;
  for (std::size_t i = 0; i < horizons.size(); ++i) {
    if (i > 0) {
      const int mid = static_cast<int>(std::lround(std::sqrt(static_cast<double>(horizons[i - 1]) * horizons[i])));
      if (mid > horizons[i - 1] && mid < horizons[i]) out.push_back(mid);
    }
    out.push_back(horizons[i]);
  }
  return out;
}

namespace {

// Whether a scale checked on rows it was not fitted on is kept: the rows held a share in
// their 90 % regions more than two standard errors from 90 % without it, and with it a
// share nearer 90 % and a density no worse. Predictions `frames` ahead from every
// `stride`-th frame overlap, so the standard error counts rows * stride / frames
// independent ones. (Where the camera's noise alone holds the measured poses a scale
// barely moves the shares, and is left at 1 rather than set where it does not matter.)
bool SafeguardHelps(const std::array<ScaledIntervals, 2>& check, int frames, int stride) {
  const double independent = std::max(1.0, check[0].rows * static_cast<double>(stride) / std::max(frames, stride));
  const double standard_error = std::sqrt(0.9 * 0.1 / independent);
  const double off_before = std::abs(check[0].inside_90 - 0.9);
  return off_before > 2 * standard_error && std::abs(check[1].inside_90 - 0.9) < off_before &&
         check[1].log_score <= check[0].log_score;
}

// Each fold's rows scored without the safeguard and with what the other folds' rows
// give, pooled over the folds: without `base`, their scale against none; with it (> 0),
// their growth on top of the base scale against the base alone.
std::array<ScaledIntervals, 2> CheckAcrossFolds(const std::vector<std::vector<SafeguardRow>>& folds, PosePart part,
                                                double base) {
  constexpr double kMost = OmniObserverModel::kMaxIntervalScale;
  std::array<ScaledIntervals, 2> out;
  for (std::size_t f = 0; f < folds.size(); ++f) {
    std::vector<SafeguardRow> others;
    for (std::size_t g = 0; g < folds.size(); ++g)
      if (g != f) others.insert(others.end(), folds[g].begin(), folds[g].end());
    if (base > 0) {
      out[0] = Pooled(out[0], ScoreIntervalScale(folds[f], part, base));
      out[1] = Pooled(out[1], ScoreIntervalScale(folds[f], part, base, ConformalIntervalGrowth(others, part, base)));
    } else {
      out[0] = Pooled(out[0], ScoreIntervalScale(folds[f], part, 1));
      out[1] = Pooled(out[1], ScoreIntervalScale(folds[f], part, ConformalIntervalScale(others, part, kMost)));
    }
  }
  return out;
}

// One part's safeguard at a horizon: checked across the folds and, where it helps, fitted
// on all rows: a growth over *scale (over_base), else the scale itself.
void FitPart(const std::vector<std::vector<SafeguardRow>>& folds, const std::vector<SafeguardRow>& all, PosePart part,
             bool over_base, int frames, int stride, double* scale, double* growth, bool* kept,
             std::array<ScaledIntervals, 2>* check) {
  *check = CheckAcrossFolds(folds, part, over_base ? *scale : 0);
  *kept = SafeguardHelps(*check, frames, stride);
  if (!*kept) return;
  if (over_base) {
    *growth = ConformalIntervalGrowth(all, part, *scale);
  } else {
    *scale = ConformalIntervalScale(all, part, OmniObserverModel::kMaxIntervalScale);
  }
}

}  // namespace

OmniIntervalSafeguard SafeguardFromFolds(const std::vector<int>& horizons,
                                         const std::vector<std::vector<std::vector<SafeguardRow>>>& rows, int stride,
                                         int min_rows, const std::vector<std::array<double, 2>>* base) {
  OmniIntervalSafeguard out;
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    OmniSafeguardHorizon h;
    h.frames = horizons[q];
    const std::vector<std::vector<SafeguardRow>>& folds = rows[q];
    std::vector<SafeguardRow> all;
    std::size_t fewest = folds.empty() ? 0 : folds.front().size();
    for (const auto& f : folds) {
      all.insert(all.end(), f.begin(), f.end());
      fewest = std::min(fewest, f.size());
    }
    h.rows = static_cast<int>(all.size());
    // The base scales as given, a growth on top of each where it helps; a part without
    // one (NaN) gets its scale from the folds.
    const bool over_position = base && std::isfinite((*base)[q][0]);
    const bool over_heading = base && std::isfinite((*base)[q][1]);
    if (over_position) h.position = (*base)[q][0];
    if (over_heading) h.heading = (*base)[q][1];
    if (folds.size() >= 2 && static_cast<int>(fewest) >= min_rows) {
      FitPart(folds, all, PosePart::kPosition, over_position, h.frames, stride, &h.position, &h.position_growth,
              &h.position_kept, &h.position_check);
      FitPart(folds, all, PosePart::kHeading, over_heading, h.frames, stride, &h.heading, &h.heading_growth,
              &h.heading_kept, &h.heading_check);
    }
    out.horizons.push_back(h);
  }
  if (base && !out.AnyKept()) {
    out.note = "no growth kept: the rows held 90 % in their 90 % regions of the base scale within two standard "
               "errors, or the other folds' growth did not bring each fold nearer without a worse log density (or "
               "too few rows)";
  } else if (!out.AnyKept()) {
    out.note = "no scale kept: the rows held 90 % in their 90 % regions within two standard errors, or the other "
               "folds' scale did not bring each fold nearer without a worse log density (or too few rows)";
  }
  return out;
}

namespace {

// One part's cell: the scale (or "-" where not kept), with its growth per unit of
// distance from the seen inputs where it has one, and the other folds' shares in the
// 90 % regions without and with their scale.
std::string SafeguardCell(double scale, double growth, bool kept, const std::array<ScaledIntervals, 2>& check) {
  if (check[0].rows == 0) return "(too few rows)";
  std::string factor = scale != 1 || (kept && growth > 0) ? PrintfNumber("x%.3g", scale) : "-";
  if (kept && growth > 0) factor += PrintfNumber("(1+%.3gd)", growth);
  char cell[128];
  std::snprintf(cell, sizeof cell, "%-14s %5.1f -> %5.1f %%", factor.c_str(), 100 * check[0].inside_90,
                100 * check[1].inside_90);
  return cell;
}

}  // namespace

std::string FormatSafeguard(const OmniIntervalSafeguard& g, double period) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line, "  %-20s %6s   %-33s %-33s\n", "horizon", "rows", "position: scale, 90 %",
                "heading: scale, 90 %");
  s << line;
  bool grows = false;
  for (const OmniSafeguardHorizon& h : g.horizons) {
    char label[64];
    std::snprintf(label, sizeof label, "%d frames (%.2f s)", h.frames, h.frames * period);
    std::snprintf(line, sizeof line, "  %-20s %6d   %-33s %-33s\n", label, h.rows,
                  SafeguardCell(h.position, h.position_growth, h.position_kept, h.position_check).c_str(),
                  SafeguardCell(h.heading, h.heading_growth, h.heading_kept, h.heading_check).c_str());
    s << line;
    grows = grows || (h.position_kept && h.position_growth > 0) || (h.heading_kept && h.heading_growth > 0);
  }
  if (grows) {
    s << "  (1+g d): the scale grows with d, a prediction's mean distance from the inputs the fit saw (wheel speeds "
         "asked and reached, over the seen commands' size)\n";
  }
  if (!g.note.empty()) s << "  " << g.note << "\n";
  return s.str();
}

}  // namespace twinsim
