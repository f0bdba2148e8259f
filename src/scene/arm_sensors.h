// The sensors an arm scene's log is recorded with: the `sensors:` block of an arm scene
// (docs/scenes.md). A real arm's controller logs encoder positions in whole counts and
// measured torques with noise, and often no velocities; these options make
// `trajectory.csv` look the same, so that identification and diagnosis can be tried on
// logs like a real arm's. They act only on what is written: the controller still sees
// the true state and sends the true command, and `tracking.csv` stays exact.
//
// The noise is drawn from the scene's seed, one stream per joint (a joint's noise does
// not depend on the other joints' settings), so the same scene and seed give the same
// bytes. Ideal sensors (the defaults) give the trial's exact q, qd and command:
//
//   ArmLog log = SensedArmLog(scene.sensors, trial, scene.seed);
//   WriteFileAtomically(out + "/trajectory.csv", FormatSensedArmLog(log));
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "control/computed_torque.h"
#include "robots/arm/arm_log.h"

namespace twinsim {

struct ArmSensorSpec {
  // dof, rad (revolute) or m (prismatic) per encoder count: logged positions are
  // rounded to whole counts, q = round(q_true / step) * step; 0 = exact. Empty: all exact.
  Eigen::VectorXd count_step;
  // dof, N·m (revolute) or N (prismatic): the standard deviation of the Gaussian noise
  // added to the logged tau; 0 = none. Empty: none.
  Eigen::VectorXd torque_noise;
  // false: the log has no qd columns (t, q, tau, qref); readers derive qd from q.
  bool log_velocities = true;

  // True when the log is the trial's exact q, qd and command.
  bool IsIdeal() const;
  // Empty when usable for an arm of `dof` joints (sizes 0 or dof, finite, steps and
  // sigmas >= 0), else what is wrong.
  bool IsValid(int dof, std::string* why) const;
};

// The log the controller would have written with these sensors: t, q (in whole counts),
// tau (the command sent, plus noise), qd (the realised velocity; absent when
// !log_velocities) and qref, as an ArmLog with sample_period the trial's sample time.
// Noise comes from Rng::Derived(seed, ...), one stream per joint. Throws InputError
// when the spec is not valid for the trial's joint count.
ArmLog SensedArmLog(const ArmSensorSpec& sensors, const TrackingTrial& trial, std::uint64_t seed);

// The CSV text of such a log in the contract's arm log format:
// `t,q1..qn,tau1..taun[,qd1..qdn][,qref1..qrefn]`, numbers by FormatCsvNumber (9
// decimals: a count finer than 1e-9 rad or m would not show).
std::string FormatSensedArmLog(const ArmLog& log);

}  // namespace twinsim
