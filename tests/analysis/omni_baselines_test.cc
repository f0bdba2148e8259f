// The no-model predictions on logs where each is exact by construction.
#include "analysis/omni_baselines.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/pose.h"

namespace twinsim {
namespace {

constexpr double kPeriod = 1.0 / 60;

OmniLog EmptyLog(int rows) {
  OmniLog log;
  log.path = "made.csv";
  log.frame_period = kPeriod;
  log.rows.resize(static_cast<std::size_t>(rows));
  for (int i = 0; i < rows; ++i) log.rows[static_cast<std::size_t>(i)].t = i * kPeriod;
  return log;
}

double WorstError(const OmniLog& log, const OmniReplayResult& r, int* predicted) {
  double worst = 0;
  *predicted = 0;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!r.predicted[i]) continue;
    ++*predicted;
    const Pose2& p = r.pose[i];
    const Pose2& m = log.rows[i].pose;
    worst = std::max({worst, std::hypot(p.x - m.x, p.y - m.y), std::abs(p.theta - m.theta)});
  }
  return worst;
}

// A robot gliding and turning at constant rates, seen with every third frame missing:
// constant velocity from the last two measured poses before the start is exact.
TEST(OmniBaselines, ConstantVelocityIsExactForAConstantVelocity) {
  OmniLog log = EmptyLog(120);
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const double t = log.rows[i].t;
    log.rows[i].pose = Pose2{0.3 + 1.2 * t, -0.1 - 0.7 * t, 0.2 + 2.5 * t};
    log.rows[i].measured = i % 3 != 2;
  }
  for (int horizon : {1, 4, 60}) {
    int predicted = 0;
    EXPECT_LT(WorstError(log, ConstantVelocityPrediction(log, horizon), &predicted), 1e-12) << horizon;
    EXPECT_GT(predicted, 120 - horizon - 4) << horizon;
  }
  int predicted = 0;
  WorstError(log, ConstantVelocityPrediction(log, 200), &predicted);
  EXPECT_EQ(predicted, 0);  // no start inside the log
}

// A robot that does exactly what it is told 5 frames late (integrated the same way:
// each frame's interval at the command in force at its start, turning included):
// the integrated command at that delay is exact at every horizon, and a frame late it is
// not.
TEST(OmniBaselines, IntegratedCommandIsExactForARobotThatObeysLate) {
  OmniLog log = EmptyLog(200);
  const int late = 5;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const double t = log.rows[i].t;
    log.rows[i].command = Twist2{0.8 * std::sin(2 * t), 0.5 * std::cos(3 * t), 1.5 * std::sin(t)};
  }
  Pose2 p{1, 2, 0.5};
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    log.rows[i].pose = p;
    const Twist2 c = i >= static_cast<std::size_t>(late) ? log.rows[i - late].command : Twist2{0, 0, 0};
    const Twist2 v = BodyToField(c, p.theta);
    p.x += v.vx * kPeriod;
    p.y += v.vy * kPeriod;
    p.theta += v.omega * kPeriod;
  }
  for (int horizon : {1, 4, 15, 60}) {
    int predicted = 0;
    const OmniReplayResult r = IntegratedCommandPrediction(log, horizon, late * kPeriod);
    const double worst = WorstError(log, r, &predicted);
    EXPECT_LT(worst, 1e-12) << horizon;
    EXPECT_GT(predicted, 200 - horizon - 2 * late) << horizon;
    const double off = WorstError(log, IntegratedCommandPrediction(log, horizon, (late + 1) * kPeriod), &predicted);
    EXPECT_GT(off, 1e-4) << horizon;
  }
}

}  // namespace
}  // namespace twinsim
