// The ball on every ball engine built (ODE, Bullet), against closed forms (docs/ball.md):
// a flat kick's speed, a chip's apex and range, the slide-to-roll transition at 5/7 of
// the speed, the rolling ball's deceleration, a ball at rest, the bounce off a robot's
// flat front, the dribbler holding the ball, and the same bytes from the same inputs.
#include "sim/ball_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/math_constants.h"
#include "test_util.h"

namespace twinsim {
namespace {

constexpr double kFrame = 1.0 / 60;  // s

class BallFieldTest : public ::testing::TestWithParam<std::string> {
 protected:
  // A field with one omni4 robot (none when `robot` is false) and the ball `ball`.
  BallField Make(const BallModel& ball, bool robot = true) {
    std::vector<OmniModel> robots;
    if (robot) robots.push_back(testing::Omni4());
    return BallField(ball, robots, FieldModel{}, MakeBallEngine(GetParam(), ball, robots, FieldModel{}));
  }
  static BallModel NoDrag() {
    BallModel b;
    b.drag = 0;
    return b;
  }
  // The ball at rest touching the front of a robot at `pose`, `lateral` m off its centre line.
  static BallState AtFront(const BallModel& ball, const Pose2& pose, double gap = 0, double lateral = 0) {
    const double f = testing::Omni4().FrontDistance() + ball.radius + gap;
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    BallState b;
    b.position = Eigen::Vector3d(pose.x + c * f - s * lateral, pose.y + s * f + c * lateral, ball.radius);
    return b;
  }
};

double Horizontal(const Eigen::Vector3d& v) { return std::hypot(v.x(), v.y()); }

TEST_P(BallFieldTest, AFlatKickLeavesWithinTwoPercentOfTheCommandedSpeedAlongTheHeading) {
  const BallModel model = NoDrag();
  const Pose2 robot{0.3, -0.2, 0.5};
  for (double speed : {2.0, 4.0, 6.0}) {
    BallField field = Make(model);
    field.Reset(AtFront(model, robot));
    // One physics step of the ball: the kick, then one step of sliding friction.
    field.StepFrame({robot}, {robot}, {BallCommand{speed, 0, 0}}, BallField::kMaxStep);
    const Eigen::Vector3d v = field.ball().velocity;
    EXPECT_NEAR(v.norm(), speed, 0.02 * speed) << GetParam() << " kick " << speed;
    EXPECT_NEAR(std::atan2(v.y(), v.x()), robot.theta, 0.01);
    EXPECT_NEAR(v.z(), 0, 0.01 * speed);
    // And a whole 60 fps frame later: sliding friction has taken mu g / 60 = 0.06 m/s.
    field.StepFrame({robot}, {robot}, {BallCommand{}}, kFrame);
    EXPECT_NEAR(field.ball().velocity.norm(), speed - model.sliding_friction * kGravity * (kFrame + BallField::kMaxStep),
                0.01 * speed);
    RecordProperty(GetParam() + "_kick_" + std::to_string(static_cast<int>(speed)) + "_error_pct",
                   std::to_string(100 * (v.norm() - speed) / speed));
  }
}

TEST_P(BallFieldTest, AKickFasterThanTheKickerIsClippedAndABallOutOfReachIsNotKicked) {
  const BallModel model = NoDrag();
  const Pose2 robot{};
  BallField field = Make(model);
  field.Reset(AtFront(model, robot));
  field.StepFrame({robot}, {robot}, {BallCommand{15, 0, 0}}, BallField::kMaxStep);
  EXPECT_NEAR(field.ball().velocity.norm(), testing::Omni4().kicker_max_speed, 0.02 * 6.5);
  field.Reset(AtFront(model, robot, 0.05));  // 5 cm off the front
  field.StepFrame({robot}, {robot}, {BallCommand{5, 0, 0}}, kFrame);
  EXPECT_LT(field.ball().velocity.norm(), 1e-6);
}

TEST_P(BallFieldTest, AChipFliesToTheClosedFormApexAndRangeWithinFivePercent) {
  const BallModel model = NoDrag();
  const Pose2 robot{-1, 0, 0};
  for (double angle_deg : {30.0, 45.0, 60.0}) {
    BallField field = Make(model);
    field.Reset(AtFront(model, robot));
    const double speed = 4, a = angle_deg * kPi / 180;
    const Eigen::Vector3d start = field.ball().position;
    field.StepFrame({robot}, {robot}, {BallCommand{speed, a, 0}}, BallField::kMaxStep);
    double apex = 0, range = 0;
    bool landed = false;
    for (int k = 0; k < 4000 && !landed; ++k) {
      const double vz_before = field.ball().velocity.z();
      field.StepFrame({robot}, {robot}, {BallCommand{}}, BallField::kMaxStep);
      const BallState& b = field.ball();
      apex = std::max(apex, b.position.z() - model.radius);
      // The first touch of the floor turns the fall round.
      if (vz_before < 0 && b.velocity.z() >= 0) {
        landed = true;
        range = Horizontal(b.position - start);
      }
    }
    ASSERT_TRUE(landed) << GetParam();
    const double vh = speed * std::cos(a), vv = speed * std::sin(a);
    const double apex_closed = vv * vv / (2 * kGravity), range_closed = 2 * vh * vv / kGravity;
    EXPECT_NEAR(apex, apex_closed, 0.05 * apex_closed) << GetParam() << " at " << angle_deg << " deg";
    EXPECT_NEAR(range, range_closed, 0.05 * range_closed) << GetParam() << " at " << angle_deg << " deg";
    RecordProperty(GetParam() + "_chip_" + std::to_string(static_cast<int>(angle_deg)) + "_apex_error_pct",
                   std::to_string(100 * (apex - apex_closed) / apex_closed));
    RecordProperty(GetParam() + "_chip_" + std::to_string(static_cast<int>(angle_deg)) + "_range_error_pct",
                   std::to_string(100 * (range - range_closed) / range_closed));
  }
}

TEST_P(BallFieldTest, AKickedBallSlidesThenRollsAtFiveSeventhsOfItsSpeed) {
  BallModel model = NoDrag();
  model.rolling_friction = 0;
  BallField field = Make(model, false);
  BallState b;
  b.position.z() = model.radius;
  b.velocity.x() = 4;  // no spin: it slides
  field.Reset(b);
  // Closed form: v = v0 - mu g t, r w = 5/2 mu g t, equal at t* = 2 v0 / (7 mu g).
  const double t_roll = 2 * 4 / (7 * model.sliding_friction * kGravity);
  const double slide_frames = std::floor(0.5 * t_roll / kFrame);
  for (int k = 0; k < slide_frames; ++k) field.StepFrame({}, {}, {}, kFrame);
  const double t = slide_frames * kFrame;
  EXPECT_NEAR(field.ball().velocity.x(), 4 - model.sliding_friction * kGravity * t, 0.01) << GetParam();
  EXPECT_NEAR(field.ball().spin.y() * model.radius, 2.5 * model.sliding_friction * kGravity * t, 0.01);
  for (int k = 0; k < 60; ++k) field.StepFrame({}, {}, {}, kFrame);
  EXPECT_NEAR(field.ball().velocity.x(), 4.0 * 5 / 7, 0.01 * 4.0 * 5 / 7) << GetParam();
  EXPECT_NEAR(field.ball().spin.y() * model.radius, field.ball().velocity.x(), 1e-3);
}

TEST_P(BallFieldTest, ARollingBallSlowsAsTheRollingFrictionClosedFormSays) {
  BallModel model = NoDrag();
  model.rolling_friction = 0.05;
  BallField field = Make(model, false);
  BallState b;
  b.position = Eigen::Vector3d(-2, 0, model.radius);
  const double v0 = 1.5;
  b.velocity.x() = v0;
  b.spin.y() = v0 / model.radius;  // rolling: w = v / r about +y
  field.Reset(b);
  const double a = 5.0 / 7 * model.rolling_friction * kGravity;  // m/s^2
  for (int second = 1; second <= 3; ++second) {
    for (int k = 0; k < 60; ++k) field.StepFrame({}, {}, {}, kFrame);
    const double expected = v0 - a * second;
    EXPECT_NEAR(field.ball().velocity.x(), expected, 0.01) << GetParam() << " at " << second << " s";
    EXPECT_NEAR(field.ball().position.x(), -2 + v0 * second - 0.5 * a * second * second, 0.01);
    RecordProperty(GetParam() + "_rolling_speed_error_at_" + std::to_string(second) + "s",
                   std::to_string(field.ball().velocity.x() - expected));
  }
  // It stops and stays stopped.
  for (int k = 0; k < 60 * 6; ++k) field.StepFrame({}, {}, {}, kFrame);
  EXPECT_LT(field.ball().velocity.norm(), 1e-3);
  const double x = field.ball().position.x();
  EXPECT_NEAR(x, -2 + v0 * v0 / (2 * a), 0.02);
}

TEST_P(BallFieldTest, ABallAtRestStaysAtRest) {
  BallField field = Make(BallModel{}, true);
  const Pose2 robot{-0.5, 0, 0};
  BallState b;
  b.position = Eigen::Vector3d(0.7, -0.4, BallModel{}.radius);
  field.Reset(b);
  for (int k = 0; k < 600; ++k) field.StepFrame({robot}, {robot}, {BallCommand{}}, kFrame);
  EXPECT_LT((field.ball().position - b.position).norm(), 1e-5) << GetParam();
  EXPECT_LT(field.ball().velocity.norm(), 1e-5);
  EXPECT_LT(field.ball().spin.norm(), 1e-3);
}

TEST_P(BallFieldTest, ABallBouncesOffTheFlatFrontPerRestitutionAndStraightBack) {
  for (double e : {0.3, 0.7}) {
    BallModel model = NoDrag();
    model.restitution = e;
    model.rolling_friction = 0;
    BallField field = Make(model);
    const Pose2 robot{0, 0, 0.6};
    // Rolling at 2 m/s straight at the front, 3 cm off its centre line: a cylinder
    // would send it off sideways, the flat front straight back.
    BallState b = AtFront(model, robot, 0.1, 0.03);
    const Eigen::Vector3d towards(-std::cos(robot.theta), -std::sin(robot.theta), 0);
    b.velocity = 2 * towards;
    b.spin = Eigen::Vector3d::UnitZ().cross(b.velocity) / model.radius;
    field.Reset(b);
    Eigen::Vector3d before = b.velocity, after = Eigen::Vector3d::Zero();
    for (int k = 0; k < 600; ++k) {
      const Eigen::Vector3d v = field.ball().velocity;
      field.StepFrame({robot}, {robot}, {BallCommand{}}, BallField::kMaxStep);
      if (field.ball().velocity.dot(towards) < 0 && v.dot(towards) > 0) {
        before = v;
        after = field.ball().velocity;
        break;
      }
    }
    const double out = -after.dot(towards), in = before.dot(towards);
    EXPECT_NEAR(out / in, e, 0.05) << GetParam() << " restitution " << e;
    const Eigen::Vector3d side(-towards.y(), towards.x(), 0);
    EXPECT_LT(std::abs(after.dot(side)), 0.03 * out) << GetParam();
    // What one-way coupling leaves out: the robot would take this impulse (N s).
    RecordProperty(GetParam() + "_bounce_" + std::to_string(e) + "_ratio", std::to_string(out / in));
    RecordProperty(GetParam() + "_bounce_impulse_Ns", std::to_string(model.mass * (in + out)));
  }
}

// Robot poses along an arc: forward at `speed`, turning at `omega`, from the origin.
Pose2 Arc(double t, double speed, double omega) {
  if (omega == 0) return Pose2{speed * t, 0, 0};
  return Pose2{speed / omega * std::sin(omega * t), speed / omega * (1 - std::cos(omega * t)), omega * t};
}

TEST_P(BallFieldTest, TheDribblerHoldsTheBallWhileTheRobotDrivesForwardAndTurnsSlowly) {
  const BallModel model;
  for (const double dribbler : {1000.0, 0.0}) {
    BallField field = Make(model);
    field.Reset(AtFront(model, Pose2{}));
    double worst_gap = 0, worst_lateral = 0;
    bool held = true;
    // 0.5 s speeding up to 1 m/s, then 3 s at 1 m/s turning at 1 rad/s.
    auto pose = [](double t) {
      if (t <= 0.5) return Pose2{t * t, 0, 0};
      Pose2 p = Arc(t - 0.5, 1, 1);
      p.x += 0.25;
      return p;
    };
    for (int k = 0; k < 210; ++k) {
      const double t = k * kFrame;
      field.StepFrame({pose(t)}, {pose(t + kFrame)}, {BallCommand{0, 0, dribbler}}, kFrame);
      const FrontContact at = BallAtFront(model, testing::Omni4(), pose(t + kFrame), field.ball());
      worst_gap = std::max(worst_gap, at.gap);
      worst_lateral = std::max(worst_lateral, std::abs(at.lateral));
      held = held && field.contact(0);
    }
    if (dribbler > 0) {
      EXPECT_TRUE(held) << GetParam();
      EXPECT_LT(worst_gap, BallField::kTouch) << GetParam();
      EXPECT_LT(worst_lateral, 0.01) << GetParam();
      RecordProperty(GetParam() + "_dribbler_worst_gap_mm", std::to_string(1000 * worst_gap));
      RecordProperty(GetParam() + "_dribbler_worst_lateral_mm", std::to_string(1000 * worst_lateral));
    } else {
      EXPECT_FALSE(held) << GetParam() << ": without the dribbler the turn loses the ball";
    }
  }
}

TEST_P(BallFieldTest, TheDribblerPullsTheBallAlongWhenTheRobotBacksOff) {
  const BallModel model;
  BallField field = Make(model);
  field.Reset(AtFront(model, Pose2{}));
  // Backwards at 0.5 m/s^2 for 1 s: the ball (7/5 m a = 0.03 N) follows on the dribbler.
  for (int k = 0; k < 60; ++k) {
    const double t0 = k * kFrame, t1 = t0 + kFrame;
    field.StepFrame({Pose2{-0.25 * t0 * t0, 0, 0}}, {Pose2{-0.25 * t1 * t1, 0, 0}}, {BallCommand{0, 0, 500}}, kFrame);
  }
  EXPECT_TRUE(field.contact(0)) << GetParam();
  EXPECT_NEAR(field.ball().velocity.x(), -0.5, 0.05);
}

// dribbler.full_speed: the pull's cap scales with the rpm below it. Backing off at
// 3 m/s^2 takes 7/5 m a = 0.19 N: the full 1 N holds the ball, a tenth of it (100 of
// 1000 rpm) does not; without full_speed, 100 rpm pulls with all of it.
TEST_P(BallFieldTest, TheDribblersPullScalesWithItsSpeedBelowFullSpeed) {
  const BallModel model;
  auto held = [&](double full_speed, double rpm) {
    OmniModel robot = testing::Omni4();
    robot.dribbler_full_speed = full_speed;
    const std::vector<OmniModel> robots{robot};
    BallField field(model, robots, FieldModel{}, MakeBallEngine(GetParam(), model, robots, FieldModel{}));
    field.Reset(AtFront(model, Pose2{}));
    for (int k = 0; k < 24; ++k) {
      const double t0 = k * kFrame, t1 = t0 + kFrame;
      field.StepFrame({Pose2{-1.5 * t0 * t0, 0, 0}}, {Pose2{-1.5 * t1 * t1, 0, 0}}, {BallCommand{0, 0, rpm}}, kFrame);
    }
    return field.contact(0);
  };
  EXPECT_TRUE(held(1000, 1000)) << GetParam();
  EXPECT_TRUE(held(1000, 5000)) << GetParam();
  EXPECT_FALSE(held(1000, 100)) << GetParam();
  EXPECT_TRUE(held(0, 100)) << GetParam();
}

TEST_P(BallFieldTest, TheSameInputsGiveTheSameBytes) {
  auto run = [&] {
    BallField field = Make(BallModel{});
    field.Reset(AtFront(BallModel{}, Pose2{}));
    std::vector<double> out;
    for (int k = 0; k < 120; ++k) {
      const double t0 = k * kFrame, t1 = t0 + kFrame;
      const BallCommand c{k == 60 ? 3.0 : 0.0, k == 60 ? 0.4 : 0.0, k < 60 ? 800.0 : 0.0};
      field.StepFrame({Arc(t0, 0.5, 0.3)}, {Arc(t1, 0.5, 0.3)}, {c}, kFrame);
      const BallState& b = field.ball();
      for (int i = 0; i < 3; ++i) out.insert(out.end(), {b.position[i], b.velocity[i], b.spin[i]});
    }
    return out;
  };
  const std::vector<double> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << GetParam();
}

TEST(BallModel, ValuesOutOfRangeAreNamed) {
  BallModel b;
  b.radius = -1;
  b.restitution = 1.5;
  std::string why;
  EXPECT_FALSE(b.IsValid(&why));
  EXPECT_NE(why.find("radius -1"), std::string::npos) << why;
  EXPECT_NE(why.find("restitution 1.5"), std::string::npos) << why;
  EXPECT_TRUE(BallModel{}.IsValid(&why)) << why;
}

TEST(BallModel, UnknownEnginesAreInputErrors) {
  EXPECT_THROW(MakeBallEngine("analytic", BallModel{}, {}, FieldModel{}), InputError);
}

INSTANTIATE_TEST_SUITE_P(Engines, BallFieldTest, ::testing::ValuesIn(AvailableBallEngines()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace
}  // namespace twinsim
