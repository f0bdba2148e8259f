// The shortest move of a robot that clears a ball (teleport_safely): after the move the
// ball is exactly `clearance` from the chassis outline, and no shorter move in any
// direction clears it (checked against a search over 720 directions).
#include "serve/ball_clearance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/math_constants.h"
#include "test_util.h"

namespace twinsim {
namespace {

// Distance (m) from the point `q` (robot frame) to the chassis: the disc of `radius`
// cut at x = front; 0 inside. Written independently of BallClearance: the nearest point
// of the disc, then of the cut (a convex set: the nearer of the clipped candidates).
double DistanceToChassis(const OmniModel& m, const Eigen::Vector2d& q) {
  const double r = m.chassis_radius, f = m.FrontDistance();
  const double hw = std::sqrt(r * r - f * f);
  if (q.norm() <= r && q.x() <= f) return 0;
  double best = 1e9;
  // The arc (where x <= f).
  const Eigen::Vector2d on_arc = q.norm() > 0 ? Eigen::Vector2d(q / q.norm() * r) : Eigen::Vector2d(-r, 0);
  if (on_arc.x() <= f) best = std::min(best, (q - on_arc).norm());
  // The flat front's segment.
  const Eigen::Vector2d on_front(f, std::clamp(q.y(), -hw, hw));
  best = std::min(best, (q - on_front).norm());
  // Corners (covered by the segment's clamp, kept for clarity).
  best = std::min({best, (q - Eigen::Vector2d(f, hw)).norm(), (q - Eigen::Vector2d(f, -hw)).norm()});
  return best;
}

Eigen::Vector2d InRobotFrame(const Pose2& pose, const Eigen::Vector2d& p) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Eigen::Vector2d d = p - Eigen::Vector2d(pose.x, pose.y);
  return Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
}

// The shortest clearing move found by searching 720 directions (bisection on length).
double SearchedShortest(const OmniModel& m, const Pose2& pose, const Eigen::Vector2d& ball, double clearance) {
  double best = 1e9;
  for (int k = 0; k < 720; ++k) {
    const double a = 2 * kPi * k / 720;
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    double lo = 0, hi = 1;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      const Pose2 moved{pose.x + mid * dir.x(), pose.y + mid * dir.y(), pose.theta};
      (DistanceToChassis(m, InRobotFrame(moved, ball)) >= clearance ? hi : lo) = mid;
    }
    best = std::min(best, hi);
  }
  return best;
}

TEST(BallClearance, MovesTheRobotTheShortestWayOutAndNoFurther) {
  const OmniModel m = testing::Omni4();
  const double clearance = 0.0215 + 0.02;
  const Pose2 pose{0.3, -0.2, 0.7};
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  auto field = [&](double x, double y) { return Eigen::Vector2d(pose.x + c * x - s * y, pose.y + s * x + c * y); };
  const double f = m.FrontDistance();
  // Ball (robot frame): before the flat front, off a corner of it, beside, behind, at the
  // centre.
  for (const Eigen::Vector2d& local : {Eigen::Vector2d(f + 0.01, 0.0), Eigen::Vector2d(f + 0.01, 0.06),
                                       Eigen::Vector2d(0.02, 0.1), Eigen::Vector2d(-0.08, -0.03),
                                       Eigen::Vector2d(0.0, 0.0)}) {
    SCOPED_TRACE("ball at (" + std::to_string(local.x()) + ", " + std::to_string(local.y()) + ") m, robot frame");
    const Eigen::Vector2d ball = field(local.x(), local.y());
    ASSERT_LT(DistanceToChassis(m, local), clearance);
    const std::optional<Eigen::Vector2d> move = BallClearance(m, pose, ball, clearance);
    ASSERT_TRUE(move.has_value());
    const Pose2 moved{pose.x + move->x(), pose.y + move->y(), pose.theta};
    EXPECT_NEAR(DistanceToChassis(m, InRobotFrame(moved, ball)), clearance, 1e-9);
    EXPECT_NEAR(move->norm(), SearchedShortest(m, pose, ball, clearance), 2e-4);
  }
  // Before the flat front the robot backs straight away from the ball, by the gap missing.
  const std::optional<Eigen::Vector2d> back = BallClearance(m, pose, field(f + 0.01, 0), clearance);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(back->norm(), clearance - 0.01, 1e-12);
  EXPECT_NEAR(back->x(), -c * (clearance - 0.01), 1e-12);
  // Already clear: nothing.
  EXPECT_FALSE(BallClearance(m, pose, field(f + clearance + 1e-6, 0), clearance).has_value());
  EXPECT_FALSE(BallClearance(m, pose, field(-m.chassis_radius - clearance - 1e-6, 0), clearance).has_value());
}

}  // namespace
}  // namespace twinsim
