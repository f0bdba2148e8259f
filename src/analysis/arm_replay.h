// A model's joint torques for a measured motion, and how far they are from the measured
// ones: what `twinsim replay` writes for an arm, and how identification is judged.
//
// PredictArmTorques gives the rigid model's torques: inverse dynamics with the joints'
// nominal viscous and Coulomb friction, at the same instant. PredictArmCommands inverts
// the whole model, effects included (arm_effects.h), into the commands a controller must
// have sent for the logged motion -- what the log's tau columns hold:
//   1. the joint needs N(t) = ID(q, qd, qdd) of the bodies with the payload lumped in,
//      plus the friction of every friction effect (ArmFrictionTorque; 0 at qd = 0; a
//      joint's pre-sliding bristles followed along the rows, ArmFrictionAlong);
//   2. joint_flexibility: N is the spring's torque on the link; the spring's deflection
//      e = thm - q solves d e' + k e = N (e = N / k without damping; implicit Euler from
//      the static deflection at the first row), and the drive must be
//      N + J_m (qdd + e''), e'' by second differences along the log;
//   3. torque_offset: the drive minus tau0 (the joint receives the command plus tau0);
//   4. torque_saturation: not inverted (a clipped torque has no unique command); the
//      command is what is needed, unclipped, and rows beyond the limit are counted;
//   5. delays: the command at t is what is needed at t + s, s = delay_samples * sample_time
//      + the joint's time_delay, interpolated linearly in the log (the last row held).
// Without effects and delay PredictArmCommands equals PredictArmTorques.
//
//   Eigen::MatrixXd tau = PredictArmCommands(model, log);  // N x n
//   TorqueErrors e = CompareArmTorques(model, log);        // per joint RMS errors
#pragma once

#include <Eigen/Core>
#include <string>

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

// The model's torques (inverse dynamics with friction) at every row of `log` (N x n),
// from its q, qd and qdd (logged or derived). Throws InputError when the joint counts differ.
Eigen::MatrixXd PredictArmTorques(const ArmModel& model, const ArmLog& log);

struct ArmCommandSummary {
  Eigen::VectorXd shift;              // s per joint: delay_samples * sample_time + time_delay
  Eigen::VectorXi beyond_saturation;  // rows per joint whose command exceeds its torque_saturation limit
  bool flexible = false;              // some joint_flexibility was inverted
};

// The commands (N x n, N·m or N) that `model` with its delay and effects needs to
// perform the logged motion (steps 1-5 above); *summary (if given) says what was done.
// Throws InputError when the joint counts differ.
Eigen::MatrixXd PredictArmCommands(const ArmModel& model, const ArmLog& log, ArmCommandSummary* summary = nullptr);

// Steps 2-5 for joint `joint` alone: the command (N) that makes it receive `needed`
// (N, the link side's torque: step 1's column), given the log's times t (N) and the
// joint's qdd (N). *beyond_saturation (if given) counts the rows beyond its limit.
Eigen::VectorXd JointCommandFromNeeded(const ArmModel& model, int joint, const Eigen::VectorXd& t,
                                       const Eigen::VectorXd& qdd, Eigen::VectorXd needed,
                                       int* beyond_saturation = nullptr);

// How long before joint `joint` receives a command it is sent (s): the model's delay
// plus the joint's time_delay (step 5).
double JointCommandLead(const ArmModel& model, int joint);

// x at times t + shift (N), linear between rows, the last row held beyond the end: what
// a signal sent `shift` early looks like in the log's time line.
Eigen::VectorXd ShiftEarlier(const Eigen::VectorXd& t, const Eigen::VectorXd& x, double shift);

// Torques Y_b(q, qd, qdd) beta at every row of `log` (N x n) straight from base
// parameters (r of `base`), which need not belong to a real arm: how an unconstrained
// estimate would predict. Throws InputError when the joint counts differ.
Eigen::MatrixXd PredictBaseTorques(const ArmModel& model, const BaseParameters& base, const Eigen::VectorXd& beta,
                                   const ArmLog& log);

struct TorqueErrors {
  Eigen::VectorXd error_rms;    // N·m or N per joint: RMS of measured - model
  Eigen::VectorXd torque_rms;   // N·m or N per joint: RMS of the measured torque
  Eigen::VectorXd relative;     // error_rms / torque_rms per joint (0 where the torque is 0)
  int rows = 0;
  // Mean over joints of error_rms / (2 effort_limit), the normalised error of
  // FloBaRoID-style reports; NaN when a joint has no effort limit.
  double normalised = 0;
};

// RMS torque errors of `model`'s commands (PredictArmCommands) on the rows [first, last)
// of `log` (last = -1: all rows).
TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, int first = 0, int last = -1);
// The same from already predicted torques (N x n, as PredictArmTorques gives).
TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, const Eigen::MatrixXd& predicted,
                               int first = 0, int last = -1);

}  // namespace twinsim
