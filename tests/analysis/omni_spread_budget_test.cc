// Where a predicted position's spread comes from (analysis/omni_spread_budget.h, issue
// 64): the observer's covariance K frames ahead is the sum of its parts (the start
// estimate carried on, the process noise, the driving noise, the drift), and on a robot
// that wanders exactly as its model says the measured error matches the predicted
// spread at every horizon.
#include "analysis/omni_spread_budget.h"

#include <gtest/gtest.h>

#include "analysis/omni_calibration.h"
#include "analysis/omni_replay.h"
#include "core/error.h"
#include "diagnosis/diagnosis_plants.h"
#include "test_util.h"

namespace twinsim {
namespace {

// omni4 wandering by 0.05, 0.05 m/s and 0.3 rad/s over 0.2 s, and drifting slowly by 0.02
// m/s and 0.05 rad/s over 3 s, drawn by the simulation.
OmniModel WanderingAndDrifting() {
  OmniModel m = testing::Omni4();
  m.driving_noise.sd = {0.05, 0.05, 0.3};
  m.driving_noise.correlation_time = 0.2;
  m.driving_noise.drift.sd = {0.02, 0.02, 0.05};
  m.driving_noise.drift.correlation_time = 3;
  m.driving_noise.simulated = true;
  return m;
}

void ExpectPartsAddUp(const OmniModel& model) {
  const OmniLog log = testing::RecordOmniPlant(model, 10, 3);
  OmniReplayOptions o;
  o.backend = "analytic";
  o.horizon = 30;
  o.also = {4};
  o.covariance = true;
  o.covariance_parts = true;
  o.stride = 5;
  const OmniReplayResult r = ReplayOmniLog(model, log, o);
  for (const OmniReplayResult* result : {&r, &r.also[0]}) {
    ASSERT_EQ(result->covariance_parts.size(), log.rows.size());
    int rows = 0;
    std::array<double, kCovarianceParts> least;
    least.fill(1e9);
    for (std::size_t i = 0; i < log.rows.size(); ++i) {
      if (!result->predicted[i]) continue;
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      for (int p = 0; p < kCovarianceParts; ++p) {
        const Eigen::Matrix3d& part = result->covariance_parts[i][static_cast<std::size_t>(p)];
        sum += part;
        least[static_cast<std::size_t>(p)] = std::min(least[static_cast<std::size_t>(p)], part.topLeftCorner<2, 2>().trace());
      }
      EXPECT_LT((sum - result->covariance[i]).norm(), 1e-12 * result->covariance[i].norm()) << i;
      ++rows;
    }
    EXPECT_GT(rows, 20);
    // Every part acts on every prediction: the estimate's uncertainty, the model's process
    // noise on its velocity, the slip, the drift where the model has one.
    for (int p = 0; p < kCovarianceParts; ++p) {
      if (p == kDrift && !model.driving_noise.drift.any()) {
        EXPECT_EQ(least[static_cast<std::size_t>(p)], 0);
      } else {
        EXPECT_GT(least[static_cast<std::size_t>(p)], 0) << kOmniCovariancePartNames[p];
      }
    }
  }
  // Parts come with the covariance only.
  o.covariance = false;
  EXPECT_THROW(ReplayOmniLog(model, log, o), InputError);
}

// With a drift and without (whose filter leaves the drift's states out).
TEST(SpreadBudget, TheCovariancesPartsAddUpToIt) {
  OmniModel without_drift = WanderingAndDrifting();
  without_drift.driving_noise.drift = {};
  for (const OmniModel& model : {WanderingAndDrifting(), without_drift}) {
    SCOPED_TRACE(model.driving_noise.drift.any() ? "with a drift" : "without");
    ExpectPartsAddUp(model);
  }
}

// The plant is the model (its slip and drift drawn by the simulation, seen by the SSL
// camera at 30 fps): the spread the filter predicts is the error it makes, within the
// scatter of a minute's predictions (measured 0.91, 0.93 and 1.00 at 4, 16 and 63 frames;
// held to 0.85 to 1.15). The slip dominates from 16 frames on; at 4 the start estimate
// (5.9 mm, against the slip's 4.2) carries the velocity the filter has not yet pinned down.
TEST(SpreadBudget, OnItsOwnRobotTheMeasuredErrorIsThePredictedSpread) {
  const OmniModel model = WanderingAndDrifting();
  const OmniLog log = testing::RecordOmniPlant(model, 60, 4);
  std::vector<OmniSpreadBudget> budgets;
  OmniLogPredictiveErrors(model, log, "analytic", {4, 16, 63}, 4, &budgets);
  ASSERT_EQ(budgets.size(), 3u);
  SCOPED_TRACE(FormatSpreadBudgets(budgets));
  for (const OmniSpreadBudget& b : budgets) {
    EXPECT_GT(b.rows, 400) << b.frames;
    EXPECT_NEAR(b.measured / b.predicted, 1.0, 0.15) << b.frames << " frames";
    double squares = b.camera * b.camera;
    for (double p : b.parts) squares += p * p;
    EXPECT_NEAR(std::sqrt(squares), b.predicted, 1e-12) << b.frames;
  }
  EXPECT_GT(budgets[1].parts[kDrivingNoise], budgets[1].parts[kStartEstimate]);
  EXPECT_GT(budgets[2].parts[kDrivingNoise], budgets[2].parts[kDrift]);
  // Pooled with itself, a budget is itself.
  const std::vector<OmniSpreadBudget> pooled = PoolSpreadBudgets({budgets, budgets});
  ASSERT_EQ(pooled.size(), budgets.size());
  EXPECT_EQ(pooled[0].rows, 2 * budgets[0].rows);
  EXPECT_NEAR(pooled[0].measured, budgets[0].measured, 1e-12);
  EXPECT_NEAR(pooled[2].parts[kDrivingNoise], budgets[2].parts[kDrivingNoise], 1e-12);
}

}  // namespace
}  // namespace twinsim
