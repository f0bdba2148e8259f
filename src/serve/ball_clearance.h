// Making room for the ball (TeleportBall.teleport_safely, docs/serve.md): the shortest
// move of a robot that leaves a ball placed at a point clear of its chassis.
//
// The chassis seen from above is the circle of chassis_radius cut by the flat front at
// FrontDistance() (the outline the ball's engines use). A ball of radius r at p is clear
// of it with a margin m when p lies outside the chassis grown by r + m: the grown shape
// is convex, so the shortest move of the robot that clears the ball is p's distance to
// the grown shape's boundary, along that boundary's normal (found exactly, from the
// shape's support function).
//
//   std::optional<Eigen::Vector2d> move = BallClearance(model, pose, ball_xy, r + m);
//   if (move) pose = Pose2{pose.x + move->x(), pose.y + move->y(), pose.theta};
#pragma once

#include <Eigen/Core>
#include <optional>

#include "core/pose.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// The shortest translation (m, field frame) of a robot with `model` at `pose` after
// which its chassis is at least `clearance` (m) from the point `ball` (m, field frame);
// nothing when it already is.
std::optional<Eigen::Vector2d> BallClearance(const OmniModel& model, const Pose2& pose, const Eigen::Vector2d& ball,
                                             double clearance);

}  // namespace twinsim
