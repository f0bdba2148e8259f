// Recorded trials for learning an arm's dynamics: tracking runs of seeded random
// references on a plant (the stand-in for the real arm), logged in the contract's arm
// log format, as a real arm's controller would log them.
//
// A training reference is a random multi-sine per joint (a FourierTrajectory,
// identification/fourier_trajectory.h, with random phases and amplitudes falling as
// 1/l) around a centre posture, so that the trials cover a region of the workspace with
// the speeds and accelerations of the tasks to come, without being any of them. The
// arm tracks it with the computed-torque controller over a nominal model `hat`
// (control/computed_torque.h) plus a seeded random torque dither, held for a few
// samples, so that torque and state are not tied together by the controller alone
// (the learner must see what torque does, not only what this controller does).
// Everything is deterministic: the same options and seed give the same log bytes.
//
//   TrainingTrialOptions options;                 // 20 s around the writing task's posture
//   ArmLog log = RecordArmTrial(plant, hat, RandomTrainingReference(hat, options, 7), options, 7);
//   WriteArmLog("trial7.csv", log, true);
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "control/writing_task.h"
#include "identification/fourier_trajectory.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

struct TrainingTrialOptions {
  double seconds = 20;            // s, length of one trial
  double fundamental = 0.2;       // Hz, of the random multi-sine
  int harmonics = 4;              // sines per joint, at l * fundamental
  Eigen::VectorXd center;         // dof, rad or m; empty = (0, 0.35, -1.1): the arm in front of
                                  // itself, tool ~0.45 m out at shoulder height (RRR arm)
  Eigen::VectorXd amplitude;      // dof, rad or m: the largest excursion; empty = (0.7, 0.45, 0.6)
  double dither = 0.03;           // torque dither sigma as a fraction of each joint's effort_limit
                                  // (1 N·m where none is given)
  int dither_hold = 10;           // samples each dither value is held
  double bandwidth = 10;          // Hz, the computed-torque controller's
  std::string backend = "analytic";  // the plant's physics
  double stop_and_go = 0.5;       // share of RecordTrainingTrials' trials that are stop-and-go
  // A torque the plant receives beyond the command, which the log does not show: an
  // effect outside every model (cogging, a spring) for tests of what a diagnosis cannot
  // name. Called once per control sample, in order; a closure with state (backlash)
  // is copied afresh for every trial. Empty: none.
  std::function<Eigen::VectorXd(const Eigen::VectorXd& q, const Eigen::VectorXd& qd)> disturbance;
  double stroke_speed = 1.5;      // rad/s, stop-and-go peak joint speed (the fastest joint)
  double stroke_acceleration = 8; // rad/s^2, stop-and-go acceleration (the fastest joint)

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// The random multi-sine reference of trial `seed` for `model` (positions within its
// limits less 0.05 rad, checked) as a FourierTrajectory. Throws InputError for invalid
// options or a reference beyond the limits.
FourierTrajectory RandomTrainingTrajectory(const ArmModel& model, const TrainingTrialOptions& options, std::uint64_t seed);

// A FourierTrajectory sampled at `sample_time` for `seconds` as a joint reference
// (the tool path p, pd, pdd is left empty).
ArmReference SampledReference(const FourierTrajectory& trajectory, double sample_time, double seconds);

// A random stop-and-go reference of trial `seed`: moves between random postures within
// centre +- amplitude, every joint on the same trapezoidal velocity profile (joint
// speed up to `stroke_speed`, acceleration `stroke_acceleration`, so the acceleration
// jumps at the ends of each phase), each followed by a random pause of 0 to 0.2 s, for
// options.seconds. Stops and sharp accelerations are where friction and delay show.
// Throws InputError for invalid options.
ArmReference RandomStopAndGoReference(const ArmModel& model, const TrainingTrialOptions& options, std::uint64_t seed);

// Runs the computed-torque controller over `hat` with the dither on `plant` along
// `reference` from its first sample, and returns the log a controller would write:
// t, q, qd (sampled), tau (the command sent at t, dither included), qref; path "".
// Where `received` is given, it gets the torque the plant received at each sample (the
// command plus options.disturbance; rows x dof). Throws InputError for invalid options,
// std::invalid_argument for mismatched shapes, CheckFailed when the arm runs away.
ArmLog RecordArmTrial(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                      const TrainingTrialOptions& options, std::uint64_t seed, Eigen::MatrixXd* received = nullptr);

// `count` trials with seeds first_seed, first_seed + 1, ...: the first
// round(count * (1 - stop_and_go)) multi-sine (RandomTrainingTrajectory), the rest
// stop-and-go (RandomStopAndGoReference), each run by RecordArmTrial.
std::vector<ArmLog> RecordTrainingTrials(const ArmModel& plant, const ArmModel& hat, const TrainingTrialOptions& options,
                                         int count, std::uint64_t first_seed);

}  // namespace twinsim
