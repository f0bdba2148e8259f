// The parameters' own uncertainty in the predictions (issue 64): identify writes the
// covariance of the response's parameters into the model (observer.parameter_covariance),
// and a replay with it adds the spread the parameters make to every prediction's
// covariance and samples (OmniReplayOptions::parameter_shifts).
#include "identification_omni/omni_identification.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "analysis/omni_replay.h"
#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

constexpr double kSigma = 0.02;   // the forward gain's standard deviation
constexpr double kSpeed = 0.8;    // m/s, the steady forward command
constexpr int kHorizon = 30;      // frames, 1 s at 30 fps

// omni4 driving straight ahead at 0.8 m/s for 6 s after a second at rest, seen at 30 fps.
OmniLog SteadyDrive(const OmniModel& model) {
  CommandSpec drive;
  drive.type = "sequence";
  drive.segments = {{1.0, Twist2{0, 0, 0}, false}, {6.0, Twist2{kSpeed, 0, 0}, false}};
  return testing::RecordLog(model, drive, 7, 1);
}

OmniReplayOptions Predicting(int samples = 0) {
  OmniReplayOptions o;
  o.backend = "analytic";
  o.horizon = kHorizon;
  o.covariance = true;
  o.samples = samples;
  return o;
}

// The robot-frame forward and sideways variance of a field-frame covariance at heading theta.
Eigen::Vector2d RobotFrameVariances(const Eigen::Matrix3d& c, double theta) {
  Eigen::Matrix2d r;
  r << std::cos(theta), std::sin(theta), -std::sin(theta), std::cos(theta);
  const Eigen::Matrix2d b = r * c.topLeftCorner<2, 2>() * r.transpose();
  return {b(0, 0), b(1, 1)};
}

// A gain known to within sigma moves the prediction one second ahead of a steady drive
// by sigma times the distance the second covers, less what the filter's slip estimate
// carries at the start (it decays over the driving noise's correlation time, 0.15 s for
// omni4): the parameters' part is that spread along the heading and nothing across it;
// it is half the difference of the predictions of the model with the gain moved either
// way by hand; and it is in the covariance the samples are drawn from.
TEST(ParameterUncertainty, AGainsSpreadMovesASteadyDrivesPredictionAlongItsHeading) {
  OmniModel model = testing::Omni4();
  const OmniLog log = SteadyDrive(model);
  model.observer.parameter_covariance = {{"forward.gain"}, Eigen::MatrixXd::Constant(1, 1, kSigma * kSigma)};
  ASSERT_EQ(model.Validate(), "");

  OmniReplayOptions with = Predicting();
  with.parameter_shifts = ParameterShiftedModels(model, log.frame_period);
  ASSERT_EQ(with.parameter_shifts.size(), 1u);
  const OmniReplayResult r = ReplayOmniLog(model, log, with);
  const OmniReplayResult without = ReplayOmniLog(model, log, Predicting());
  ASSERT_EQ(r.parameter_covariance.size(), log.rows.size());
  EXPECT_TRUE(without.parameter_covariance.empty());

  // The gain moved by hand, each model replayed for its mean.
  std::array<OmniReplayResult, 2> by_hand;
  for (int side = 0; side < 2; ++side) {
    OmniModel m = model;
    m.observer.parameter_covariance = {};
    m.effects.axis_scale[0] = 1 + (side == 0 ? kSigma : -kSigma);
    OmniReplayOptions mean = Predicting();
    mean.covariance = false;
    by_hand[static_cast<std::size_t>(side)] = ReplayOmniLog(m, log, mean);
  }

  const double reach = kSpeed * kHorizon * log.frame_period;  // m in one horizon
  const double tau = model.driving_noise.correlation_time;
  int rows = 0;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!r.predicted[i] || log.rows[i].t < 4 || i < kHorizon) continue;  // from 3 s of steady driving on
    ++rows;
    const Eigen::Matrix3d& part = r.parameter_covariance[i];
    const Eigen::Vector3d d(0.5 * (by_hand[0].pose[i].x - by_hand[1].pose[i].x),
                            0.5 * (by_hand[0].pose[i].y - by_hand[1].pose[i].y),
                            0.5 * (by_hand[0].pose[i].theta - by_hand[1].pose[i].theta));
    EXPECT_LT((part - d * d.transpose()).norm(), 0.01 * part.norm()) << "t = " << log.rows[i].t;
    EXPECT_LT((r.covariance[i] - without.covariance[i] - part).norm(), 1e-12) << "t = " << log.rows[i].t;
    // Along the path the robot took over the horizon, and across it.
    const Pose2& from = log.rows[i - kHorizon].pose;
    const Eigen::Vector2d v =
        RobotFrameVariances(part, std::atan2(log.rows[i].pose.y - from.y, log.rows[i].pose.x - from.x));
    EXPECT_LT(std::sqrt(v[0]), kSigma * reach) << "t = " << log.rows[i].t;
    EXPECT_GT(std::sqrt(v[0]), kSigma * (reach - kSpeed * tau)) << "t = " << log.rows[i].t;
    EXPECT_LT(std::sqrt(v[1]), 0.05 * std::sqrt(v[0])) << "t = " << log.rows[i].t;
    EXPECT_LT(std::sqrt(part(2, 2)), 1e-3) << "t = " << log.rows[i].t;
  }
  EXPECT_GT(rows, 60);

  // 4000 draws at one row: their forward spread is the covariance's, the part included
  // (the variance of 4000 draws' variance: 2.2 %).
  with.samples = 4000;
  const OmniReplayResult drawn = ReplayOmniLog(model, log, with);
  const std::size_t at = log.rows.size() - 40;
  ASSERT_TRUE(drawn.predicted[at]);
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  for (const Pose2& p : drawn.samples[at]) {
    const Eigen::Vector2d e(p.x - drawn.pose[at].x, p.y - drawn.pose[at].y);
    c += e * e.transpose() / 4000.0;
  }
  Eigen::Matrix3d sample = Eigen::Matrix3d::Zero();
  sample.topLeftCorner<2, 2>() = c;
  const double theta = log.rows[at].pose.theta;
  EXPECT_NEAR(RobotFrameVariances(sample, theta)[0] / RobotFrameVariances(drawn.covariance[at], theta)[0], 1, 0.08);
  EXPECT_GT(RobotFrameVariances(drawn.covariance[at], theta)[0],
            RobotFrameVariances(without.covariance[at], theta)[0] + 0.5 * std::pow(kSigma * reach, 2));
}

// Every direction of a covariance is replayed, the widest first; a limit the model has
// off is left out; a parameter identify does not fit is refused with the model's file named.
TEST(ParameterUncertainty, ShiftsFollowTheCovariancesDirectionsAndRefuseUnknownNames) {
  OmniModel model = testing::Omni4();
  model.source_path = "robot.yaml";
  Eigen::MatrixXd c(2, 2);
  c << 4e-4, 1e-4, 1e-4, 1e-4;
  model.observer.parameter_covariance = {{"forward.gain", "sideways.gain"}, c};
  const auto shifts = ParameterShiftedModels(model, 1.0 / 30);
  ASSERT_EQ(shifts.size(), 2u);
  // The pairs' gains lie either side of the model's, by the covariance's square root:
  // sum_l (d_l d_l^T) = C to first order.
  Eigen::Matrix2d sum = Eigen::Matrix2d::Zero();
  for (const auto& pair : shifts) {
    const Eigen::Vector2d d(0.5 * (pair[0].effects.axis_scale[0] - pair[1].effects.axis_scale[0]),
                            0.5 * (pair[0].effects.axis_scale[1] - pair[1].effects.axis_scale[1]));
    sum += d * d.transpose();
    EXPECT_TRUE(pair[0].observer.parameter_covariance.empty());
  }
  EXPECT_LT((sum - c).norm(), 1e-3 * c.norm());
  const auto& widest = shifts[0][0].effects.axis_scale;
  const auto& other = shifts[1][0].effects.axis_scale;
  EXPECT_GT(std::hypot(widest[0] - 1, widest[1] - 1), std::hypot(other[0] - 1, other[1] - 1));

  // A speed limit the model has off has no spread: left out, the gains' directions stay.
  Eigen::MatrixXd with_limit = Eigen::MatrixXd::Identity(3, 3) * 1e-4;
  with_limit.topLeftCorner<2, 2>() = c;
  ASSERT_EQ(model.effects.v_max, 0);
  model.observer.parameter_covariance = {{"forward.gain", "sideways.gain", "velocity_saturation.v_max"}, with_limit};
  const auto without_limit = ParameterShiftedModels(model, 1.0 / 30);
  ASSERT_EQ(without_limit.size(), 2u);
  for (const auto& pair : without_limit) EXPECT_EQ(pair[0].effects.v_max, 0);

  model.observer.parameter_covariance = {{"driving_noise.forward"}, Eigen::MatrixXd::Constant(1, 1, 1e-4)};
  try {
    ParameterShiftedModels(model, 1.0 / 30);
    ADD_FAILURE() << "a noise's spread is not a response parameter";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("robot.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("driving_noise.forward"), std::string::npos) << e.what();
  }
  model.observer.parameter_covariance = {};
  EXPECT_TRUE(ParameterShiftedModels(model, 1.0 / 30).empty());
}

}  // namespace
}  // namespace twinsim
