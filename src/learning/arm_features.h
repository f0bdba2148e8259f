// The learned arm model's inputs and outputs: what a predictor of an arm's next joint
// state sees (issue 5; the arm's counterpart of omni_features.h).
//
// Inputs at sample i: the last `history` samples j = i-history+1..i, oldest first,
// each as, per joint: the position (a revolute joint as sin q and cos q, since gravity
// and the mass matrix depend on q through them; a prismatic joint as q in m), then the
// velocities qd_j, then the drive torques that act over [t_j, t_j + Ts) (the command
// logged D = command_lag samples earlier: the model's delay_samples). So a predictor
// learns the arm's dynamics with its friction and effects, and the simulation loop adds
// the delay exactly as for the physics backends. For a horizon H > 1 the torques acting
// over samples i+1..i+H-1 follow (dof more numbers each).
//
// Outputs: the change of the joint state from sample i to i+H, as
//   (q_{i+H} - q_i - H Ts qd_i,  qd_{i+H} - qd_i)     (rad or m; rad/s or m/s)
// the position part without the straight-line share H Ts qd_i that the inputs already
// give: left in, it would dwarf the part that dynamics decides (~1000 times smaller at
// 1 kHz), and a network's normalised outputs would spend their precision on it.
//
//   ArmFeatureLayout layout = ArmLayoutFor(model, 4, 1);
//   EncodeArmInputs(layout, q, qd, tau, x.data());   // q, qd: history x dof, row-major
//   DecodeArmOutputs(layout, y, q_i, qd_i, &q_next, &qd_next);
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

class ArmNominalStep;  // arm_nominal_step.h

struct ArmFeatureLayout {
  std::string joints;       // one letter per joint: 'R' revolute (sin, cos), 'P' prismatic (q)
  int history = 4;          // samples of history
  int horizon = 1;          // H, samples ahead
  int command_lag = 1;      // D, samples from logging a command to it acting
  double sample_time = 0;   // s, Ts

  // Residual predictors only: the nominal model's one-sample errors over the history's
  // history - 1 transitions follow the inputs above (EncodeNominalErrors).
  bool nominal_errors = false;

  int dof() const { return static_cast<int>(joints.size()); }
  // Numbers per history sample: positions (2 per revolute joint), velocities, torques.
  int per_sample() const;
  // The states and torques (EncodeArmInputs).
  int num_base_inputs() const { return per_sample() * history + dof() * (horizon - 1); }
  int num_inputs() const { return num_base_inputs() + (nominal_errors ? 2 * dof() * (history - 1) : 0); }
  int num_outputs() const { return 2 * dof(); }
  // Torque rows the inputs need: history + H - 1.
  int num_torques() const { return history + horizon - 1; }
};

// The layout for `model`'s joints and delay at its sample time.
ArmFeatureLayout ArmLayoutFor(const ArmModel& model, int history, int horizon);

// Writes the state and torque inputs into out (num_base_inputs()). q, qd: `history`
// rows of dof numbers, oldest first, row-major; tau: num_torques() rows of dof torques
// acting over samples i-history+1 .. i+H-1.
void EncodeArmInputs(const ArmFeatureLayout& layout, const double* q, const double* qd, const double* tau,
                     double* out);

// The nominal model's errors over the window's transitions, the inputs that follow the
// base ones when layout.nominal_errors: for j = 0 .. history-2, the measured state
// j + 1 minus the nominal model's step from state j under tau_j, as (q (dof), qd (dof)).
// What the nominal model has lately missed (friction it lacks, a payload, an offset)
// mostly persists for the next sample, so this tells a residual predictor much of its
// next correction. Writes 2 dof (history - 1) numbers; arguments as EncodeArmInputs.
void EncodeNominalErrors(const ArmFeatureLayout& layout, ArmNominalStep& nominal, const double* q, const double* qd,
                         const double* tau, double* out);

// The outputs (num_outputs()) for the state (q_i, qd_i) -> (q_{i+H}, qd_{i+H}).
void EncodeArmOutputs(const ArmFeatureLayout& layout, const double* q_i, const double* qd_i, const double* q_later,
                      const double* qd_later, double* out);

// The state H samples after (q_i, qd_i) from outputs y (num_outputs()).
void DecodeArmOutputs(const ArmFeatureLayout& layout, const double* y, const double* q_i, const double* qd_i,
                      double* q_later, double* qd_later);

// Training samples: x (N x num_inputs), y (N x num_outputs), in time order.
struct ArmDataset {
  Eigen::MatrixXd x;
  Eigen::MatrixXd y;
  int rows() const { return static_cast<int>(x.rows()); }
  // Appends rows (x, y).
  void Append(const Eigen::MatrixXd& more_x, const Eigen::MatrixXd& more_y);
};

// A log as the predictor sees it: the state of each row and the torque acting over it
// (row-major N x dof; the torque logged command_lag rows earlier, unknown before).
struct ArmSequence {
  int dof = 0;
  std::vector<double> q, qd, acting;  // rows x dof, row-major
  int first_known_torque = 0;          // the first row whose acting torque is in the log
  int rows() const { return dof ? static_cast<int>(q.size()) / dof : 0; }
};
ArmSequence ToArmSequence(const ArmLog& log, const ArmFeatureLayout& layout);

// Every window of a sequence whose newest sample lies in [first, last] (with its H-ahead
// sample in the sequence and every acting torque known); appends to *data and returns
// the number added. With `nominal` (a residual predictor's base, arm_nominal_step.h) the
// outputs are what remains after the nominal model's step: the measured outputs minus
// the nominal model's (its state H samples after sample i under the acting torques).
// A layout with nominal_errors needs `nominal` (else std::invalid_argument).
int AppendArmSamples(const ArmSequence& seq, const ArmFeatureLayout& layout, int first, int last, ArmDataset* data,
                     ArmNominalStep* nominal = nullptr);

}  // namespace twinsim
