// Scores of a predictive distribution (analysis/omni_calibration.h) on rows drawn from
// known Gaussians: calibrated rows cover 50 % and 90 %, give a flat PIT and beat one
// constant spread when the spread varies from row to row; rows twice as wide as stated
// show as a U; the constant spread of round rows is their own. And the replay's shorter
// horizons (OmniReplayOptions::also) are the same predictions as a replay at that horizon.
#include "analysis/omni_calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <functional>
#include <limits>

#include "core/math_constants.h"
#include "core/rng.h"
#include "estimation/wandering_plant.h"
#include "test_util.h"

namespace twinsim {
namespace {

// n rows whose stated covariance is a random rotated ellipse (axes 0.5 to 10 mm, evenly
// in their logarithm, and their ratio up to 3; heading 2 to 20 mrad), their errors drawn
// from that covariance times `truth_scale`.
std::vector<PredictiveError> DrawnRows(int n, double truth_scale, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<PredictiveError> rows;
  for (int k = 0; k < n; ++k) {
    const double a = 0.0005 * std::exp(rng.Uniform(0, std::log(20.0))), b = a * rng.Uniform(1.0 / 3, 1);
    const double h = rng.Uniform(0.002, 0.02);
    const double phi = rng.Uniform(0, kPi);
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    r.topLeftCorner<2, 2>() << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
    PredictiveError row;
    row.c = r * Eigen::Vector3d(a * a, b * b, h * h).asDiagonal() * r.transpose();
    const Eigen::Matrix3d l = row.c.llt().matrixL();
    row.e = truth_scale * l * Eigen::Vector3d(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    rows.push_back(row);
  }
  return rows;
}

TEST(Calibration, RowsDrawnFromTheirOwnGaussiansAreCalibratedAndBeatAConstantSpread) {
  const std::vector<PredictiveError> rows = DrawnRows(20000, 1.0, 3);
  const OmniCalibration c = Calibrate(rows, ConstantSpread(DrawnRows(20000, 1.0, 4)));
  // 20000 independent rows: a share's standard error is at most 0.35 %; 4 of them.
  EXPECT_NEAR(c.position_50, 0.5, 0.014);
  EXPECT_NEAR(c.position_90, 0.9, 0.009);
  EXPECT_NEAR(c.heading_50, 0.5, 0.014);
  EXPECT_NEAR(c.heading_90, 0.9, 0.009);
  for (int b = 0; b < kPitBins; ++b) {
    EXPECT_NEAR(c.position_pit[b] / 20000.0, 0.1, 0.009) << b;
    EXPECT_NEAR(c.heading_pit[b] / 20000.0, 0.1, 0.009) << b;
  }
  // Spreads that vary twentyfold between rows: the right one per row beats the best
  // single spread: measured 12.6 % (3.6 % for spreads evenly between 1 and 8 mm). The
  // energy score rewards the right spread only mildly: what it mostly measures is the
  // distance from the mean, which the baseline shares.
  EXPECT_GT(c.EnergyGain(), 0.1);
  // The log score's expectation: (3 + E log det(2 pi C)) / 2.
  double expected = 0;
  for (const PredictiveError& r : rows) expected += 0.5 * (3 + std::log((2 * kPi * r.c).determinant()));
  EXPECT_NEAR(c.log_score, expected / rows.size(), 0.03);
  EXPECT_NEAR(MeanLogScore(rows), c.log_score, 1e-12);
}

// Issue 64: rows split by how far their inputs lie from the fit's. Calibrated rows near
// the seen inputs and rows three times wider than stated beyond them: scored apart, the
// near ones hold their 90 % and the far ones fall short; every row in one bin, none
// counted twice, and the whole is what it was without the split.
TEST(Calibration, RowsSplitByTheirDistanceFromTheSeenInputs) {
  std::vector<PredictiveError> near = DrawnRows(4000, 1.0, 5), far = DrawnRows(2000, 3.0, 6);
  for (std::size_t i = 0; i < near.size(); ++i) near[i].input_distance = 0.3 * static_cast<double>(i % 3) / 2;  // 0 to 0.3
  for (PredictiveError& r : far) r.input_distance = 1.5;
  std::vector<std::vector<PredictiveError>> rows(1, near);
  rows[0].insert(rows[0].end(), far.begin(), far.end());
  const std::vector<int> horizons{16};
  std::vector<OmniCalibration> bins;
  int total = 0;
  for (std::size_t b = 0; b + 1 < kCalibrationDistances.size(); ++b) {
    bins.push_back(CalibrateRows(rows, horizons, 1 / 30.0, kCalibrationDistances[b], kCalibrationDistances[b + 1])[0]);
    total += bins.back().rows;
    EXPECT_EQ(bins.back().frames, 16);
  }
  EXPECT_EQ(total, 6000);
  EXPECT_EQ(bins[0].rows + bins[1].rows, 4000);  // 0 and 0.15 below 0.25, 0.3 above
  EXPECT_EQ(bins[2].rows, 2000);
  EXPECT_NEAR(bins[0].position_90, 0.9, 0.02);
  EXPECT_LT(bins[2].position_90, 0.5);
  const OmniCalibration whole = CalibrateRows(rows, horizons, 1 / 30.0)[0];
  const OmniCalibration direct = Calibrate(rows[0], ConstantSpread(rows[0]));
  EXPECT_EQ(whole.rows, 6000);
  EXPECT_EQ(whole.position_90, direct.position_90);
  EXPECT_EQ(whole.log_score, direct.log_score);
  EXPECT_NEAR(whole.seconds, 16 / 30.0, 1e-12);
}

// Issue 64: the rows by quarter of their measured turn rate. Calibrated rows while the
// robot turns slowly and rows three times wider than stated in the fastest half: the
// quarters hold a quarter of the rows each, slowest first, with their ranges; the slow
// ones hold their 90 % and the fast ones fall short.
TEST(Calibration, RowsSplitByQuarterOfTheirTurnRate) {
  std::vector<PredictiveError> slow = DrawnRows(2000, 1.0, 7), fast = DrawnRows(2000, 3.0, 8);
  for (std::size_t i = 0; i < slow.size(); ++i) slow[i].turn_rate = 0.001 * static_cast<double>(i);  // 0 to 2 rad/s
  for (std::size_t i = 0; i < fast.size(); ++i) fast[i].turn_rate = 3 + 0.001 * static_cast<double>(i);
  std::vector<std::vector<PredictiveError>> rows(2, fast);  // out of order: sorted by the split
  rows[0].insert(rows[0].end(), slow.begin(), slow.end());
  rows[1].resize(3);  // a horizon with too few rows for every quarter
  const auto quarters = CalibrateRowsByTurnRate(rows, {16, 63}, 1 / 30.0);
  ASSERT_EQ(quarters.size(), 2u);
  const std::array<double, 4> from{0, 1, 3, 4}, to{0.999, 1.999, 3.999, 4.999};
  for (std::size_t k = 0; k < 4; ++k) {
    const OmniTurnQuarter& q = quarters[0][k];
    EXPECT_EQ(q.calibration.rows, 1000) << k;
    EXPECT_EQ(q.calibration.frames, 16);
    EXPECT_NEAR(q.from, from[k], 1e-9) << k;
    EXPECT_NEAR(q.to, to[k], 1e-9) << k;
    if (k < 2) EXPECT_NEAR(q.calibration.position_90, 0.9, 0.03) << k;
    else EXPECT_LT(q.calibration.position_90, 0.5) << k;
  }
  int short_rows = 0;
  for (const OmniTurnQuarter& q : quarters[1]) short_rows += q.calibration.rows;
  EXPECT_EQ(short_rows, 3);
  EXPECT_EQ(quarters[1][0].calibration.rows, 0);
}

// The turn rate a row is split by: the mean of |turn rate| over the prediction's frames,
// the robot's speed of turning even where it turns back and forth (a net turn of none).
TEST(Calibration, TheMeasuredTurnRateIsTheSpeedOfTurning) {
  OmniLog log;
  log.frame_period = 1 / 30.0;
  for (int k = 0; k <= 120; ++k) {
    OmniLogRow row;
    row.t = k / 30.0;
    // 2 rad/s one way for 10 frames, then back for 10.
    const int phase = k % 20;
    row.pose.theta = 2.0 / 30 * (phase < 10 ? phase : 20 - phase);
    log.rows.push_back(row);
  }
  for (std::size_t i : {20u, 47u, 120u}) EXPECT_NEAR(MeasuredTurnRate(log, i, 16), 2.0, 1e-9) << i;
  EXPECT_NEAR(MeasuredTurnRate(log, 5, 16), 2.0, 1e-9);  // the frames there are before the log's start
  EXPECT_EQ(MeasuredTurnRate(log, 0, 16), 0);
  log.rows[30].measured = false;  // its pose interpolated, as the reader gives it: the same
  EXPECT_NEAR(MeasuredTurnRate(log, 40, 16), 2.0, 1e-9);
}

TEST(Calibration, RowsTwiceAsWideAsStatedShowAsAU) {
  const OmniCalibration c = Calibrate(DrawnRows(5000, 2.0, 5), 0.005);
  EXPECT_LT(c.position_50, 0.2);  // P(d^2 <= 1.386 / 4) = 1 - exp(-0.173) = 0.16
  EXPECT_LT(c.position_90, 0.5);  // 1 - exp(-0.576) = 0.44
  EXPECT_GT(c.position_pit[kPitBins - 1], 4 * c.position_pit[kPitBins / 2]);
  EXPECT_GT(c.heading_pit[0], 2 * c.heading_pit[kPitBins / 2]);
  EXPECT_GT(c.heading_pit[kPitBins - 1], 2 * c.heading_pit[kPitBins / 2]);
}

// Rows as the learned backend makes them: for each of `truth`'s rows, the covariance is
// the mean square of kSampleDraws draws from it (about the known mean) plus the known
// `camera` part, and the error is drawn from the truth plus the camera.
constexpr int kSampleDraws = 16;
std::vector<PredictiveError> EstimatedRows(const std::vector<PredictiveError>& truth,
                                           const std::function<Eigen::Matrix3d(const PredictiveError&)>& camera,
                                           std::uint64_t seed) {
  Rng rng(seed);
  std::vector<PredictiveError> rows;
  for (const PredictiveError& t : truth) {
    const Eigen::Matrix3d l = t.c.llt().matrixL();
    Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
    for (int k = 0; k < kSampleDraws; ++k) {
      const Eigen::Vector3d d = l * Eigen::Vector3d(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
      s += d * d.transpose() / kSampleDraws;
    }
    PredictiveError row;
    const Eigen::Matrix3d known = camera(t);
    const Eigen::Matrix3d lc = (t.c + known).llt().matrixL();
    row.e = lc * Eigen::Vector3d(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    row.c = s + known;
    row.draws = kSampleDraws;
    row.drawn = s;
    rows.push_back(row);
  }
  return rows;
}

// Rows whose covariance is the mean square of n = 16 draws about the known mean (the
// learned backend's rollouts), plus a known camera part: scored as Gaussians they are too
// narrow (F(2, 15) against chi-square: the 50 % ellipse holds 46 %, the 90 % one 85 %);
// scored as the Student t the estimate implies they hold their shares, and the t
// log density is least at the true spread, where the Gaussian one asks for a third more
// variance (n / (n - p - 1) = 16 / 12).
TEST(Calibration, ACovarianceEstimatedFromDrawsIsScoredAsStudentsT) {
  constexpr int kDraws = kSampleDraws;
  const std::vector<PredictiveError> truth = DrawnRows(20000, 1.0, 7);
  const Eigen::Matrix3d camera = Eigen::Vector3d(1e-8, 1e-8, 1e-6).asDiagonal();  // 0.1 mm, 1 mrad: small
  const std::vector<PredictiveError> estimated =
      EstimatedRows(truth, [&](const PredictiveError&) { return camera; }, 8);
  const OmniCalibration c = Calibrate(estimated, 0.005);
  EXPECT_NEAR(c.position_50, 0.5, 0.014);
  EXPECT_NEAR(c.position_90, 0.9, 0.009);
  EXPECT_NEAR(c.heading_50, 0.5, 0.014);
  EXPECT_NEAR(c.heading_90, 0.9, 0.009);
  for (int b = 0; b < kPitBins; ++b) EXPECT_NEAR(c.position_pit[b] / 20000.0, 0.1, 0.009) << b;
  // The same rows taken as known Gaussians: too narrow.
  std::vector<PredictiveError> as_known = estimated;
  for (PredictiveError& r : as_known) r.draws = 0;
  const OmniCalibration g = Calibrate(as_known, 0.005);
  EXPECT_NEAR(g.position_50, 0.45, 0.02);  // F(2, 15): 1 - (1 + 1.386 / 16)^-7.5 = 0.46
  EXPECT_NEAR(g.position_90, 0.85, 0.02);  // 1 - (1 + 4.605 / 16)^-7.5 = 0.85
  // The variance scale each log density likes best (a scan of k in c -> k c).
  auto best_scale = [](std::vector<PredictiveError> rows) {
    double best = 0, best_cost = std::numeric_limits<double>::infinity();
    for (double k = 0.7; k <= 1.8; k += 0.01) {
      std::vector<PredictiveError> scaled = rows;
      for (PredictiveError& r : scaled) r.c *= k, r.drawn *= k;
      const double cost = MeanLogScore(scaled);
      if (cost < best_cost) best_cost = cost, best = k;
    }
    return best;
  };
  EXPECT_NEAR(best_scale(estimated), 1.0, 0.05);
  EXPECT_NEAR(best_scale(as_known), 16.0 / 12, 0.07);
  // A row without draws, or whose drawn part is nothing, is a known Gaussian.
  EXPECT_TRUE(std::isinf(EffectiveDraws(truth[0], PosePart::kPosition)));
  PredictiveError held = estimated[0];
  held.drawn.setZero();
  EXPECT_TRUE(std::isinf(EffectiveDraws(held, PosePart::kPose)));
  // The camera's known part adds degrees of freedom: with one as large as the drawn part
  // the sum's are four times the draws (Satterthwaite), and the shares still hold.
  PredictiveError even = estimated[0];
  even.c = 2 * even.drawn;
  EXPECT_NEAR(EffectiveDraws(even, PosePart::kPosition), 4 * kDraws, 1e-9);
  EXPECT_NEAR(EffectiveDraws(even, PosePart::kHeading), 4 * kDraws, 1e-9);
}

// As above with a camera part as large as the prediction's (the degrees of freedom of
// the sum from Satterthwaite's approximation): the shares within 2 %.
TEST(Calibration, AnEstimatedCovarianceWithAnEqualKnownPartHoldsItsShares) {
  // The camera's part: as large as the prediction's.
  const std::vector<PredictiveError> rows =
      EstimatedRows(DrawnRows(20000, 1.0, 11), [](const PredictiveError& t) { return t.c; }, 12);
  const OmniCalibration c = Calibrate(rows, 0.005);
  EXPECT_NEAR(c.position_50, 0.5, 0.02);
  EXPECT_NEAR(c.position_90, 0.9, 0.015);
  EXPECT_NEAR(c.heading_50, 0.5, 0.02);
  EXPECT_NEAR(c.heading_90, 0.9, 0.015);
}

// For round Gaussian rows the energy score is proper: the spread that scores best is the
// rows' own (here 3 mm), within the quadrature's and the sample's error.
TEST(Calibration, TheConstantSpreadOfRoundRowsIsTheirOwn) {
  Rng rng(9);
  std::vector<PredictiveError> rows(20000);
  for (PredictiveError& r : rows) r.e << 0.003 * rng.Gaussian(), 0.003 * rng.Gaussian(), 0;
  EXPECT_NEAR(ConstantSpread(rows), 0.003, 0.0001);
  EXPECT_EQ(ConstantSpread({}), 0.0);
  const OmniCalibration none = Calibrate({}, 0);
  EXPECT_EQ(none.rows, 0);
  EXPECT_EQ(none.EnergyGain(), 0.0);
}

// One 16-frame prediction gives the 4-frame one on its way: the replay's `also` rows are
// those of a replay at 4 frames from the same start frames, pose and covariance.
TEST(Calibration, ShorterHorizonsOnTheWayAreTheSamePredictions) {
  const testing::PlantRecording rec = testing::RecordWanderingPlant(testing::WanderingPlant{}, 8, 11);
  const OmniModel model = testing::Omni4();
  OmniReplayOptions longer;
  longer.backend = "analytic";
  longer.horizon = 16;
  longer.also = {4};
  longer.covariance = true;
  longer.stride = 3;
  longer.stride_origin = 0;
  OmniReplayOptions shorter = longer;
  shorter.horizon = 4;
  shorter.also.clear();
  const OmniReplayResult a = ReplayOmniLog(model, rec.log, longer);
  const OmniReplayResult b = ReplayOmniLog(model, rec.log, shorter);
  ASSERT_EQ(a.also.size(), 1u);
  const OmniReplayResult& at4 = a.also[0];
  int same = 0;
  for (std::size_t i = 0; i < rec.log.rows.size(); ++i) {
    if (!at4.predicted[i] || !b.predicted[i]) continue;
    ++same;
    EXPECT_NEAR(at4.pose[i].x, b.pose[i].x, 1e-12) << i;
    EXPECT_NEAR(at4.pose[i].theta, b.pose[i].theta, 1e-12) << i;
    EXPECT_NEAR((at4.covariance[i] - b.covariance[i]).norm(), 0, 1e-15) << i;
  }
  EXPECT_GT(same, 100);
  // The prediction's own covariance (without the camera's) is the filter's uncertainty
  // carried ahead under the model's noise: never zero on a predicted row.
  for (std::size_t i = 0; i < rec.log.rows.size(); ++i) {
    if (a.predicted[i]) {
      EXPECT_GT(a.covariance[i].trace(), 0) << i;
    }
  }
  // Predicting 16 frames ahead is wider than 4.
  const std::vector<PredictiveError> far = PredictiveErrors(rec.log, a), near = PredictiveErrors(rec.log, b);
  ASSERT_FALSE(far.empty());
  ASSERT_FALSE(near.empty());
  EXPECT_GT(far.back().c.trace(), near.back().c.trace());
  // Refused where it cannot apply.
  OmniReplayOptions bad = longer;
  bad.also = {16};
  EXPECT_THROW(ReplayOmniLog(model, rec.log, bad), InputError);
  bad.also = {4};
  bad.state = OmniReplayState::kTracker;
  EXPECT_THROW(ReplayOmniLog(model, rec.log, bad), InputError);
}

}  // namespace
}  // namespace twinsim
