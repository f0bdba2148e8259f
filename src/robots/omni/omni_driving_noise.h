// One frame of an omni robot's driving noise (OmniDrivingNoise, docs/models.md): the
// slip the wheels do not see, a first-order Gauss-Markov process per robot axis sampled
// exactly over the frame,
//   s <- a s + sqrt(1 - a^2) sd(v, dv/dt, omega) w,   a = exp(-dt / correlation_time),
// (and its drift b, where it has one, the same at its own spreads and time),
// its spread stationary at sd (at the speed, acceleration and turn rate of the robot's
// own, wheel, velocity), and the body moved on by s dt in its own frame. The simulation loop
// (Simulation) and the learned backend's sampled predictions (analysis/omni_replay.h)
// draw it the same way.
//
//   std::array<double, 3> slip{};            // starts at rest
//   Pose2 next = SlipPose(noise, dt, v, v_before, pose, &slip, &rng);
#pragma once

#include <array>

#include "core/pose.h"
#include "core/rng.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// Advances *slip (forward, sideways m/s; turn rad/s) by one frame of `dt` seconds from
// *rng and returns `pose` moved on by it. `velocity` and `velocity_before` are the
// robot's own (wheel) velocity now and a frame ago, robot frame. With `drift` and a
// noise that has one (OmniDrivingNoise::drift), the drift too, the same way at its own
// spreads and correlation time (three more draws, after the slip's), and the pose moved
// by both.
Pose2 SlipPose(const OmniDrivingNoise& noise, double dt, const Twist2& velocity, const Twist2& velocity_before,
               const Pose2& pose, std::array<double, 3>* slip, Rng* rng, std::array<double, 3>* drift = nullptr);

// A drift's start: drawn from its stationary spread (a run has its drift from the first
// frame on), from *rng; zero for a noise without one.
std::array<double, 3> StartDrift(const OmniDrivingNoise& noise, Rng* rng);

}  // namespace twinsim
