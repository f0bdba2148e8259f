#include "robots/omni/omni_driving_noise.h"

#include <algorithm>
#include <cmath>

namespace twinsim {

Pose2 SlipPose(const OmniDrivingNoise& noise, double dt, const Twist2& velocity, const Twist2& velocity_before,
               const Pose2& pose, std::array<double, 3>* slip, Rng* rng) {
  const double a = std::exp(-dt / noise.correlation_time);
  const double speed = std::hypot(velocity.vx, velocity.vy);
  const double acceleration = std::hypot(velocity.vx - velocity_before.vx, velocity.vy - velocity_before.vy) / dt;
  std::array<double, 3>& s = *slip;
  for (std::size_t c = 0; c < 3; ++c) {
    s[c] = a * s[c] + std::sqrt(1 - a * a) * rng->Gaussian(noise.Spread(static_cast<int>(c), speed, acceleration, velocity.omega));
  }
  const double cos_t = std::cos(pose.theta), sin_t = std::sin(pose.theta);
  return Pose2{pose.x + (cos_t * s[0] - sin_t * s[1]) * dt, pose.y + (sin_t * s[0] + cos_t * s[1]) * dt,
               pose.theta + s[2] * dt};
}

OmniTypicalMotion TypicalMotion(const std::vector<const OmniLog*>& logs) {
  double speed = 0, turn = 0;
  long count = 0;
  for (const OmniLog* log : logs) {
    for (std::size_t i = 1; i < log->rows.size(); ++i) {
      const OmniLogRow &a = log->rows[i - 1], &b = log->rows[i];
      if (!a.measured || !b.measured || b.t <= a.t) continue;
      speed += std::hypot(b.pose.x - a.pose.x, b.pose.y - a.pose.y) / (b.t - a.t);
      turn += std::abs(WrapAngle(b.pose.theta - a.pose.theta)) / (b.t - a.t);
      ++count;
    }
  }
  if (count == 0) return {};
  return {std::min(speed / static_cast<double>(count), 3.0), std::min(turn / static_cast<double>(count), 20.0)};
}

}  // namespace twinsim
