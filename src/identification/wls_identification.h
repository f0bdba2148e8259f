// Identification of an arm's base parameters and friction from measured motion and
// torques by weighted least squares (seed 001, section IV; Gautier's method).
//
// The torques are linear in the base parameters beta = K pi (robots/arm/arm_regressor.h):
//   tau(k) = Y_b(q(k), qd(k), qdd(k)) beta + noise.
// Stacking the samples of every log gives an overdetermined system W beta = tau. It is
// solved first by ordinary least squares; then joint j's rows are weighted by 1 / sigma_j,
// the standard deviation of that joint's residual, and solved again (weighted least
// squares, which is what makes joints with large and small torques count alike), by QR
// throughout. The stacked system is never stored: each joint's rows are folded into a
// small triangular factor as they are computed, so 100 000 samples of a 7-joint arm
// take a fraction of the memory of W. The relative standard deviation of each estimate
// comes from (W_w^T W_w)^-1, scaled by the weighted residual's variance. Optionally a
// constant torque offset per joint (a torque sensor's bias) is estimated alongside, and a
// Coulomb level that varies along each joint's travel (position_friction, arm_effects.h):
// with K knots evenly spread over the positions the logs visit, the level is
//   c(q) = f_c + sum_{k=2..K} d_k h_k(q),
// h_k the hat function that is 1 at knot k and 0 at its neighbours (linear between), so
// f_c is the level at the first knot and f_c + d_k at knot k; the columns sign(q̇) h_k(q)
// join the joint's equations beside its constant Coulomb column.
//
// Data that does not excite some base parameter (a joint that never moves, or a motion
// too poor to tell combinations apart) is refused with an InputError naming them. The
// base parameters are then mapped back to a full standard parameter vector close to the
// a-priori model's (the minimum-norm correction with K pi = beta), and, if that gives a
// link with non-positive mass or an inertia that no real body has, or negative
// friction, to the physically consistent one that fits the weighted torques best
// (identification/physical_consistency.h), with the shift reported.
// The result passes ArmModel::Validate().
//
//   WlsIdentificationSummary summary;
//   ArmModel identified = IdentifyArmByLeastSquares(a_priori, {ReadArmLog("run1.csv")}, {}, &summary);
//   std::puts(summary.FullReport().c_str());
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

struct WlsIdentificationOptions {
  int decimate = 1;                  // use every k-th row of each log
  bool skip_filter_edges = true;     // leave out each log's edge_samples rows at both ends (derived qd/qdd)
  bool weighted = true;              // weight each joint by 1 / its OLS residual std dev (false: OLS only)
  // Also estimate a constant offset per joint: measured torque = model torque + offset
  // (a torque sensor's bias; the contract's torque_offset effect is minus this).
  bool torque_offsets = false;
  // Also estimate each moving joint's Coulomb level at this many knots along its travel
  // (position_friction; 0: one level, 2..kMaxProfileKnots).
  int position_friction_knots = 0;
  // Also estimate a torque that varies along each moving joint's travel, at this many
  // knots (position_torque: a cable, a spring, a tilt; 0: none, 2..kMaxProfileKnots).
  // Beside torque offsets its first knot's level is the offset's (0 in the effect).
  int position_torque_knots = 0;
  double still_range = 1e-3;         // rad or m: a joint whose q spans less than this never moves
  // A moving joint's rows where |q̇| is below this share of its RMS speed (over all logs)
  // are left out of its own equations: at rest a joint holds anywhere within its friction
  // band, where the model's c sign(q̇) says nothing (a drive that dwells between moves
  // otherwise trades its Coulomb friction for viscous). 0: every row.
  double rest_share = 0.02;
  double max_condition_number = 1e5; // of the column-scaled stacked regressor; above: parameters not excited
  int base_samples = 200;            // random states for finding the base parameters
  std::uint64_t base_seed = 1;
  // True when usable; otherwise *why says what is wrong.
  bool IsValid(std::string* why) const;
};

struct WlsIdentificationSummary {
  int dof = 0;
  int logs = 0;
  int samples = 0;                     // samples used (all logs, after trimming and decimation)
  Eigen::VectorXi rest_rows;           // per joint: of those, rows at rest left out of its equations
  Eigen::VectorXd rest_speed;          // per joint: the speed below which a row counts as at rest (rad/s or m/s)
  int base_parameters = 0;             // r; the vectors below hold r base parameters, then the offsets
  std::vector<std::string> names;      // base parameters, each as its standard combination; "offset<j>"
  std::vector<std::string> descriptions;  // the same in words ("Coulomb friction of joint 3")
  Eigen::VectorXd a_priori;            // K pi of the a-priori model (offsets 0)
  Eigen::VectorXd ordinary;            // OLS estimate
  Eigen::VectorXd identified;          // WLS estimate (OLS when not weighted)
  Eigen::VectorXd relative_std;        // %, 100 sigma(beta_k) / |beta_k|
  Eigen::VectorXd consistent;          // K pi of the returned model (and the offsets refitted to it)
  Eigen::VectorXd offsets;             // N·m or N per joint (empty without torque_offsets): measured - model at rest
  // With position_friction_knots K: the unknowns after the offsets are, per moving joint
  // (position_joints, 0-based), d_2..d_K; the returned model's dry level at each knot
  // (dof x K, N·m or N; a joint without its own knots holds its constant level), the
  // knots from position_from to position_to (per joint, rad or m; set with either profile).
  int position_knots = 0;
  std::vector<int> position_joints;
  Eigen::MatrixXd position_levels;
  Eigen::VectorXd position_from, position_to;
  std::vector<std::string> position_notes;  // a knot's level below zero, held at zero
  // With position_torque_knots K: then per moving joint the position torque's e_k (k from
  // 2 beside offsets, else from 1), measured - model as the offsets; the returned model's
  // position_torque levels p_k = -e_k (dof x K; 0 for a joint without knots).
  int torque_knots = 0;
  Eigen::MatrixXd torque_levels;
  Eigen::VectorXd joint_sigma;         // N·m or N per joint, the OLS residual std dev (the weights' inverse)
  Eigen::VectorXd torque_rms;          // N·m or N per joint, measured torque RMS over the samples used
  Eigen::VectorXd error_rms_a_priori;  // N·m or N per joint, torque error RMS of the a-priori model
  Eigen::VectorXd error_rms_identified;  // ... of the WLS estimate
  Eigen::VectorXd error_rms_model;     // ... of the returned (consistent) model
  double condition_number = 0;         // of the column-scaled weighted stacked regressor
  bool consistency_fixed = false;      // the minimum-norm mapping was not physical and was fixed
  double consistency_shift_max_std = 0;  // largest |consistent - identified| in standard deviations
  std::vector<std::string> consistency_notes;  // what was not physical before the fix
  int consistency_iterations = 0;      // of the consistent fit (0: not needed)
  std::vector<int> still_joints;       // 1-based joints that never move
  double seconds = 0;                  // wall time

  // One line without the wall time (deterministic), and the tables (with it).
  std::string BriefReport() const;
  std::string FullReport() const;
};

// Identifies `a_priori`'s base parameters and friction from `logs` and returns the
// model with them (kinematics, limits and names unchanged). Its effects: the estimated
// torque offsets as torque_offset effects (tau0 = -offset); with position friction a
// position_friction effect per moving joint over its lowest knot's level (the joint's
// Coulomb friction); with a position torque a position_torque effect per moving joint;
// the a-priori model's
// time_delay, torque_saturation and joint_flexibility kept; its friction effects,
// payload and torque offsets dropped (the identified parameters hold their torques). Throws InputError for invalid options, a log
// whose joint count differs from the model's, too few samples, data that does not
// excite some parameter (named in words), data whose physically consistent fit still is
// no valid arm, or an a-priori model that is not physical.
ArmModel IdentifyArmByLeastSquares(const ArmModel& a_priori, const std::vector<ArmLog>& logs,
                     const WlsIdentificationOptions& options, WlsIdentificationSummary* summary = nullptr);

// Per joint, the speed below which a row of `logs` counts as at rest: `share` of the
// joint's RMS speed over the rows between each log's edge_samples (all rows without
// skip_edges), every decimate-th. Such rows say nothing of c sign(q̇).
Eigen::VectorXd ArmRestSpeeds(const std::vector<ArmLog>& logs, double share, int decimate = 1, bool skip_edges = true);

// Per row and joint (rows x dof), true where `log`'s joint is at rest or near it: |q̇|
// below rest_speed, and where q̇ is derived, every row within one period of the
// derivatives' cut-off of such a row (the zero-phase filter smears a stop over that
// reach, so the derived q̇ there still moves while the joint already sticks).
Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> ArmRestRows(const ArmLog& log, const Eigen::VectorXd& rest_speed);

// The torques of the unknowns beyond the base parameters (offsets, position friction's
// d_k, position torque's e_k) at the estimate `x` (an estimate vector of *summary: identified, consistent, ...)
// for every row of `log` (rows x dof).
Eigen::MatrixXd ExtraTorques(const WlsIdentificationSummary& summary, const Eigen::VectorXd& x, const ArmLog& log);

// The identification's base parameters of `model` (FindBaseParameters with the options' samples and seed).
BaseParameters IdentificationBase(const ArmModel& model, const WlsIdentificationOptions& options);

// A base parameter in words: "Coulomb friction of joint 3", "mass of link 2, regrouped with 2 others".
std::string DescribeBaseParameter(const ArmModel& model, const BaseParameters& base, int k);

}  // namespace twinsim
