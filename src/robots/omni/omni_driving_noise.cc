#include "robots/omni/omni_driving_noise.h"

#include <cmath>

namespace twinsim {

Pose2 SlipPose(const OmniDrivingNoise& noise, double dt, const Twist2& velocity, const Twist2& velocity_before,
               const Pose2& pose, std::array<double, 3>* slip, Rng* rng, std::array<double, 3>* drift) {
  const double a = std::exp(-dt / noise.correlation_time);
  const double speed = std::hypot(velocity.vx, velocity.vy);
  const double acceleration = std::hypot(velocity.vx - velocity_before.vx, velocity.vy - velocity_before.vy) / dt;
  std::array<double, 3>& s = *slip;
  for (std::size_t c = 0; c < 3; ++c) {
    s[c] = a * s[c] + std::sqrt(1 - a * a) * rng->Gaussian(noise.Spread(static_cast<int>(c), speed, acceleration, velocity.omega));
  }
  std::array<double, 3> moving = s;
  if (drift && noise.drift.any()) {
    const double b = std::exp(-dt / noise.drift.correlation_time);
    for (std::size_t c = 0; c < 3; ++c) {
      (*drift)[c] = b * (*drift)[c] + std::sqrt(1 - b * b) * rng->Gaussian(noise.drift.sd[c]);
      moving[c] += (*drift)[c];
    }
  }
  const double cos_t = std::cos(pose.theta), sin_t = std::sin(pose.theta);
  return Pose2{pose.x + (cos_t * moving[0] - sin_t * moving[1]) * dt, pose.y + (sin_t * moving[0] + cos_t * moving[1]) * dt,
               pose.theta + moving[2] * dt};
}

std::array<double, 3> StartDrift(const OmniDrivingNoise& noise, Rng* rng) {
  std::array<double, 3> b{0, 0, 0};
  if (!noise.drift.any()) return b;
  for (std::size_t c = 0; c < 3; ++c) b[c] = rng->Gaussian(noise.drift.sd[c]);
  return b;
}

}  // namespace twinsim
