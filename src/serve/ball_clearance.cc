#include "serve/ball_clearance.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace twinsim {

std::optional<Eigen::Vector2d> BallClearance(const OmniModel& model, const Pose2& pose, const Eigen::Vector2d& ball,
                                             double clearance) {
  // The ball in the robot's frame.
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Eigen::Vector2d d = ball - Eigen::Vector2d(pose.x, pose.y);
  const Eigen::Vector2d p(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  const double radius = model.chassis_radius;
  const double front = std::min(model.FrontDistance(), radius);
  const double half_width = model.FrontHalfWidth();
  const double corner_angle = std::atan2(half_width, front);  // the front's corners seen from the centre

  // The chassis' support function h(psi) (its extent along the direction psi): the arc's
  // radius where the arc is outermost, else the nearer corner's projection. The grown
  // shape's is h + clearance, and for a point inside a convex shape the distance to its
  // boundary is the least of h(psi) + clearance - p.n(psi) over all directions.
  auto gap = [&](double psi) {
    const double h = std::abs(psi) >= corner_angle ? radius : radius * std::cos(corner_angle - std::abs(psi));
    return h + clearance - (p.x() * std::cos(psi) + p.y() * std::sin(psi));
  };
  // The least lies where gap's derivative vanishes on one of its pieces (towards p on the
  // arc, away from a corner on the corners' pieces) or at the pieces' joints (0, the
  // corners' directions).
  std::vector<double> candidates = {0, corner_angle, -corner_angle, std::atan2(p.y(), p.x()),
                                    std::atan2(p.y() - half_width, p.x() - front),
                                    std::atan2(p.y() + half_width, p.x() - front)};
  double best = 0, best_psi = 0;
  bool first = true;
  for (double psi : candidates) {
    const double g = gap(psi);
    if (first || g < best) {
      best = g;
      best_psi = psi;
      first = false;
    }
  }
  if (best <= 0) return std::nullopt;  // already clear
  // The robot moves against the normal, by the gap: the ball ends on the grown boundary.
  const Eigen::Vector2d n_robot(std::cos(best_psi), std::sin(best_psi));
  const Eigen::Vector2d n_field(c * n_robot.x() - s * n_robot.y(), s * n_robot.x() + c * n_robot.y());
  return Eigen::Vector2d(-best * n_field);
}

}  // namespace twinsim
