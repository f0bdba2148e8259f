// A model's joint torques for a measured motion, and how far they are from the measured
// ones: what `twinsim replay` writes for an arm, and how identification is judged.
//
//   Eigen::MatrixXd tau = PredictArmTorques(model, log);   // N x n
//   TorqueErrors e = CompareArmTorques(model, log);        // per joint RMS errors
#pragma once

#include <Eigen/Core>
#include <string>

#include "io/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

// The model's torques (inverse dynamics with friction) at every row of `log` (N x n),
// from its q, qd and qdd (logged or derived). Throws InputError when the joint counts differ.
Eigen::MatrixXd PredictArmTorques(const ArmModel& model, const ArmLog& log);

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

// RMS torque errors of `model` on the rows [first, last) of `log` (last = -1: all rows).
TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, int first = 0, int last = -1);
// The same from already predicted torques (N x n, as PredictArmTorques gives).
TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, const Eigen::MatrixXd& predicted,
                               int first = 0, int last = -1);

}  // namespace twinsim
