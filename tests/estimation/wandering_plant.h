// A test plant that wanders as a real small-size robot does, written apart from
// twinsim's models: a kinematic robot whose body velocity follows its delayed command
// through a first-order lag per robot axis, plus driving noise (a Gauss-Markov velocity
// disturbance in the robot frame, correlated over a few frames), seen by a camera with
// noise, lost frames and optionally a gap of seconds. No PID, no wheels, no engine.
// Optionally the real robot's further traits: a lag in the field frame, braking faster
// than accelerating, a turn-rate limit, a turn when driven sideways, smoothed poses.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/pose.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim::testing {

struct WanderingPlant {
  double frame_rate = 60;                        // Hz
  int delay_frames = 4;                          // from command to camera pose, frames
  std::array<double, 3> gain{0.8, 0.7, 0.6};     // velocity reached per unit command, forward, sideways, turn
  std::array<double, 3> lag{0.08, 0.1, 0.06};    // s, first-order time constants per axis
  std::array<double, 3> noise_sd{0.12, 0.15, 1.0};  // m/s, m/s, rad/s: the driving noise's stationary spread
  double noise_correlation = 0.2;                // s, its correlation time
  // A spread that grows with speed: noise_sd times sqrt(f^2 + (1 - f^2) min(1, (v / V)^2)),
  // f = noise_still (1: the same at every speed), V = noise_full_speed (m/s), v the
  // lagged velocity's translational speed: f of it standing still, all of it from V on.
  double noise_still = 1;
  double noise_full_speed = 1;                   // m/s
  // And with turn rate, the same way (times the speed's factor): noise_not_turning of it
  // while the lagged turn rate is 0, all of it from noise_full_turn (rad/s) on.
  double noise_not_turning = 1;
  double noise_full_turn = 2;                    // rad/s
  double camera_xy = 0.001;                      // m
  double camera_theta = 0.01;                    // rad
  double drop = 0.1;                             // share of frames the camera loses
  double gap_start = -1;                         // s, where the camera loses the robot for gap_seconds (< 0: never)
  double gap_seconds = 0;
  double max_speed = 1.2;                        // m/s, of the random commands
  double max_turn = 3;                           // rad/s
  // What the real SSL robot of issue 40 showed besides (all off by default):
  bool field_frame_lag = false;    // the lagged translation keeps its direction in the field (momentum)
  double braking = 1;              // the lag's time constants times this while an axis slows down
  double turn_limit = 0;           // rad/s, the turn rate the robot reaches at most (0: none)
  double turn_per_sideways = 0;    // rad/s of turn per m/s of sideways command
  double camera_smoothing = 0;     // s, the camera's poses through a first-order smoother (a vision filter)
  // A run's own drift: a velocity (forward, sideways m/s, turn rad/s, robot frame) the
  // body adds the whole recording through, constant, the same whatever it is commanded
  // (a floor, a battery, a worn wheel of the day); a test gives each recording its own.
  std::array<double, 3> run_drift{0, 0, 0};
  // Effects of the diagnosis's vocabulary, as this plant's own code makes them (all off
  // by default), for the omni diagnosis's tests on a plant written apart from twinsim:
  double motor_lag = 0;                // s, a first-order lag in series before the axes' own (all three)
  double speed_scale = 1;              // every axis's gain times this (a wheel radius error)
  double max_translation = 0;          // m/s, the translational target's length at most (0: none)
  double max_acceleration = 0;         // m/s^2, the translational acceleration's length at most (0: none)
  double turn_per_metre = 0;           // rad of extra turn per metre driven
  double turn_per_forward = 0;         // rad/s of turn per m/s of forward command
  double sideways_per_forward = 0;     // m/s sideways per m/s of forward command
};

struct PlantRecording {
  OmniLog log;                       // what the camera saw, read back as a log file
  std::vector<Pose2> truth;          // per frame
  std::vector<Twist2> velocity;      // per frame, robot frame
};

// `seconds` of random piecewise-constant driving, deterministic per seed.
PlantRecording RecordWanderingPlant(const WanderingPlant& plant, double seconds, std::uint64_t seed);

// `base` (an Omni4) set up to resemble the plant's response (gain and lag per axis, the
// delay, fast ramps, and the traits above) and its driving noise, but not its structure:
// a PID-driven body on wheels. The nearest a twinsim model comes to the plant's own model.
OmniModel ResemblingModel(OmniModel base, const WanderingPlant& plant);

// The constant-velocity extrapolation (no model) at `horizon` frames: RMS position
// error over the rows with a measurement whose origin frame has two measured rows
// at or before it.
double ConstantVelocityRmse(const OmniLog& log, int horizon, std::size_t first_row = 0);

}  // namespace twinsim::testing
