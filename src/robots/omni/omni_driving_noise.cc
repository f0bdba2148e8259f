#include "robots/omni/omni_driving_noise.h"

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

}  // namespace twinsim
