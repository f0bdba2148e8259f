// Planar poses and velocities of a robot on the field.
//
// Pose2 is a pose in the field frame (x, y in m, theta in rad, counter-clockwise).
// Twist2 is a velocity; whether it is in the field or the robot frame is said by the
// variable that holds it (the robot frame is x forward, y left).
#pragma once

#include <cmath>

#include "core/math_constants.h"

namespace twinsim {

struct Pose2 {
  double x = 0;      // m
  double y = 0;      // m
  double theta = 0;  // rad
};

struct Twist2 {
  double vx = 0;     // m/s
  double vy = 0;     // m/s
  double omega = 0;  // rad/s
};

// Wraps an angle into [-pi, pi).
inline double WrapAngle(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a - kPi;
}

// Rotates the planar vector (x, y) by angle a.
inline void Rotate(double a, double x, double y, double* out_x, double* out_y) {
  const double c = std::cos(a), s = std::sin(a);
  *out_x = c * x - s * y;
  *out_y = s * x + c * y;
}

// A velocity in the robot frame expressed in the field frame (omega unchanged).
inline Twist2 BodyToField(const Twist2& body, double theta) {
  Twist2 out = body;
  Rotate(theta, body.vx, body.vy, &out.vx, &out.vy);
  return out;
}

// A velocity in the field frame expressed in the robot frame with heading theta.
inline Twist2 FieldToBody(const Twist2& field, double theta) {
  Twist2 out = field;
  Rotate(-theta, field.vx, field.vy, &out.vx, &out.vy);
  return out;
}

// The robot-frame velocity (in the frame of `after`) that moves `before` to `after` in
// one frame at `frame_rate` Hz: the finite difference of two consecutive observed poses,
// heading change wrapped.
inline Twist2 BodyVelocityBetween(const Pose2& before, const Pose2& after, double frame_rate) {
  const Twist2 field{(after.x - before.x) * frame_rate, (after.y - before.y) * frame_rate,
                     WrapAngle(after.theta - before.theta) * frame_rate};
  return FieldToBody(field, after.theta);
}

inline bool IsFinite(const Pose2& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}
inline bool IsFinite(const Twist2& v) {
  return std::isfinite(v.vx) && std::isfinite(v.vy) && std::isfinite(v.omega);
}

}  // namespace twinsim
