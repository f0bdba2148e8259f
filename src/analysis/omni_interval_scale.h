// The intervals' safeguard (issue 64; docs/identification.md, "The intervals'
// safeguard"): a split-conformal scale of an omni model's predictive covariance.
//
// A row's predictive distribution of the measured position is N(mean, s^2 P + R), P the
// filter's predicted covariance of the position, R the camera's; the heading's the same
// with its own s. The row's score is the smallest s whose 90 % region
// (d^2 = e' (s^2 P + R)^-1 e <= chi2_2(0.9), or z^2 <= chi2_1(0.9) for the heading)
// holds it. With n held-out rows, the ceil((n + 1) 0.9)-th smallest score makes the
// 90 % regions hold at least 90 % of new rows exchangeable with those (split conformal
// prediction: Vovk, Gammerman and Shafer 2005; Lei et al. 2018): by construction on rows
// of the same logs driven the same way, and no promise beyond them.
//
// Out of the fit's reach the model's own error grows (left-out logs): a prediction whose
// inputs lie a mean distance d from those the fit saw (robots/omni/omni_seen_inputs.h)
// is scaled by s_b (1 + g d), s_b the scale of rows within the fit's reach (the held-out
// blocks'). A row's score is the smallest g that holds it, (s_i / s_b - 1) / d_i (d at
// least kMinGrowthDistance), and the same rank of the scores gives g: the regions of
// s_b (1 + g d) grow with g on every row, so the guarantee above holds for it (a
// normalised nonconformity score: Papadopoulos, Gammerman and Vovk 2008, a
// nearest-neighbour distance the difficulty). The shape, linear in d from s_b at the
// seen inputs, is the model error's first order: an error that is zero where the fit
// saw the inputs and grows with the step away from them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// One held-out row: the measured pose minus the predicted, the prediction's covariance
// and the camera's (of the model that predicted it).
struct SafeguardRow {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  Eigen::Matrix3d predicted = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d camera = Eigen::Matrix3d::Zero();
  double distance = 0;  // the prediction's mean distance from the seen inputs
  // 0: `predicted` is known (the observer's); else it was estimated from this many
  // sampled rollouts (the learned backend's), and the row's regions and density are
  // those of the Student t it implies (analysis/omni_calibration.h, PredictiveError), so
  // that a scale fitted here holds where `compare` scores it.
  int draws = 0;
};

// Observer rows (c is the prediction's covariance plus `camera`) as safeguard rows,
// appended to *out.
void AppendSafeguardRows(const std::vector<PredictiveError>& rows, const Eigen::Matrix3d& camera,
                         std::vector<SafeguardRow>* out);

// The shares of `part` (position or heading) inside the central 50 % and 90 % regions,
// and its mean negative log density (nats per row), with the predicted covariance scaled.
struct ScaledIntervals {
  int rows = 0;
  double inside_50 = 0, inside_90 = 0;
  double log_score = 0;
};

// The conformal scale of `part` (PosePart::kPosition or kHeading) for the central
// `level` regions on `rows`, within [1 / most, most]; 1 without rows.
double ConformalIntervalScale(const std::vector<SafeguardRow>& rows, PosePart part, double most, double level = 0.9);

// `rows` scored with the prediction's covariance of `part` scaled by `scale` (1 + growth
// * distance).
ScaledIntervals ScoreIntervalScale(const std::vector<SafeguardRow>& rows, PosePart part, double scale,
                                   double growth = 0);

// The conformal growth of `part` on `rows` over the base scale `base`: the scale of a
// row d from the seen inputs is base (1 + g d); within [0, kMaxIntervalGrowth]; 0
// without rows.
double ConformalIntervalGrowth(const std::vector<SafeguardRow>& rows, PosePart part, double base, double level = 0.9);
// The least distance a growth's score divides by: a row at the seen inputs that the base
// scale does not hold asks for a growth, not for an infinite one. (So the guarantee is
// for rows at least this far from the seen inputs; nearer, the base scale answers.)
inline constexpr double kMinGrowthDistance = 0.1;

// Pools two scores of different rows by their row counts.
ScaledIntervals Pooled(const ScaledIntervals& a, const ScaledIntervals& b);

// The safeguard at one horizon: the scales of the position's and the heading's
// predicted covariance, each kept only where the rows held a share in their 90 % regions
// more than two standard errors from 90 % and each fold's rows, scored with the scale of
// the other folds' rows, come nearer 90 % without a worse log density (the scale written
// is then the one of all rows; 1 where not kept). Over a base (SafeguardFromFolds'
// `base`): the scales are the base's, and what is kept, and checked, is each one's growth.
struct OmniSafeguardHorizon {
  int frames = 0;
  int rows = 0;  // all folds'
  double position = 1, heading = 1;
  double position_growth = 0, heading_growth = 0;  // per unit of distance from the seen inputs
  bool position_kept = false, heading_kept = false;
  // Each fold with the other folds' scale (or growth), pooled: without (first) and with
  // (second).
  std::array<ScaledIntervals, 2> position_check, heading_check;
};

struct OmniIntervalSafeguard {
  std::string on;  // the folds: "held-out blocks" (its two halves) or "left-out logs, ..."; "" when not fitted
  std::vector<OmniSafeguardHorizon> horizons;
  std::string note;  // why none is kept, where none is
  bool AnyKept() const;
  // The model's observer.interval_scale: every horizon when any scale differs from 1 or
  // grows, else empty.
  std::vector<OmniObserverModel::IntervalScale> Scales() const;
};

// The horizons a safeguard is fitted at: `horizons`, and between two of them their
// geometric mean, so that a scale read between horizons is interpolated over at most a
// doubling.
std::vector<int> SafeguardHorizons(std::vector<int> horizons);

// The fewest predictions at a horizon that check or scale the intervals there: per fold
// of a safeguard (a half of identify's held-out blocks, a left-out log, a fold of
// train's held-out rows), below which nothing is scaled, and in identify's calibration
// as a whole, below which identify says the horizon is not checked.
inline constexpr int kSafeguardLeastRows = 20;

// The safeguard from rows[h][f], the rows of fold f at horizons[h], predicted from every
// `stride`-th frame (their overlap sets the standard error). Folds with fewer than
// `min_rows` rows at a horizon leave it unscaled. With `base` ((position, heading) per
// horizon: the scales within the fit's reach), those scales are kept as they are and
// each gets a growth with the distance from the seen inputs where the folds ask for one
// (the same rule, the base in place of no scale); a NaN base (no scale within the fit's
// reach was checked there) leaves the folds to fit that scale itself.
OmniIntervalSafeguard SafeguardFromFolds(const std::vector<int>& horizons,
                                         const std::vector<std::vector<std::vector<SafeguardRow>>>& rows, int stride,
                                         int min_rows, const std::vector<std::array<double, 2>>* base = nullptr);

// The safeguard as a table: per horizon (`period` s a frame) its rows and, for the
// position and the heading, the scale kept ("-" where none) and each fold's share in its
// 90 % regions without and with the other folds' scale; then the note where none is kept.
std::string FormatSafeguard(const OmniIntervalSafeguard& g, double period);

}  // namespace twinsim
