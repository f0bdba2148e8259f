// Model-based tracking control of an arm (seed 001, section V, the writing task of
// Fig. 6 and 7), and a tracking trial that runs a controller on the arm simulation and
// says how well the model served.
//
// Two controllers, each over a model `hat` that may differ from the plant:
//   computed torque   tau = M_hat(q) (qdd_r + Kd (qd_r - qd) + Kp (q_r - q)) + h_hat(q, qd) + f_hat(qd)
//                     with Kp = w^2, Kd = 2 zeta w (1/s^2, 1/s; the same for every joint)
//                     so that, with the exact model and no delay, every joint's error obeys
//                     e'' + 2 zeta w e' + w^2 e = 0;
//   PD + feedforward  tau = InverseDynamics_hat(q_r, qd_r, qdd_r) + Kp' (q_r - q) + Kd' (qd_r - qd)
//                     with Kp'_i = M_hat_ii(q_r(0)) w^2, Kd'_i = M_hat_ii(q_r(0)) 2 zeta w
//                     (N·m/rad, N·m·s/rad): the same bandwidth at the start posture.
// h_hat is C qd + g and f_hat the viscous and Coulomb friction of the model's joints.
// The arm's command reaches the joints D = model.delay_samples samples late, so the
// feedforward (computed torque: q̈_r and the friction's velocity; PD + feedforward: the
// whole InverseDynamics_hat term) takes the reference `preview` samples ahead (D by
// default), while the feedback acts on the error sampled now.
//
// RunTrackingTrial builds an ArmSimulation of the plant on a backend, starts it on the
// reference at rest, runs the controller along the reference and returns, per sample,
// the positions, the controller's output, its model-based part, the torque the plant
// really needed (the plant's own inverse dynamics along the realised motion), tracking
// errors and how often each joint hit its effort limit.
//
//   ArmModel plant = LoadArmModel("models/rrr_rod_tip.yaml"), hat = LoadArmModel("models/rrr.yaml");
//   ArmReference ref = WritingTaskReference(hat, {});
//   TrackingTrial trial = RunTrackingTrial(plant, "analytic", hat, ref, {});
//   std::cout << trial.BriefReport() << "\n";
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>

#include "backends/arm_backend_factory.h"
#include "control/writing_task.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

enum class TrackingController { kComputedTorque, kPdFeedforward };

// "computed_torque" or "pd_feedforward".
std::string TrackingControllerName(TrackingController controller);

// Feedback gains, one per joint: for computed torque in 1/s^2 and 1/s (they multiply
// M_hat), for PD + feedforward in N·m/rad and N·m·s/rad.
struct TrackingGains {
  Eigen::VectorXd kp;  // dof
  Eigen::VectorXd kd;  // dof
};

struct TrackingOptions {
  TrackingController controller = TrackingController::kComputedTorque;
  double bandwidth = 10;      // Hz: the closed loop's natural frequency w / (2 pi)
  double damping = 1;         // zeta; 1 = critically damped
  int preview = -1;           // samples the feedforward looks ahead; -1 = the model's delay_samples
  bool friction = true;       // compensate the model's friction
  // Computed torque: evaluate the friction compensation f_hat at the reference velocity
  // (previewed) instead of the measured one. At the writing task's corners every joint
  // stops, and the Coulomb term's sign(qd) of a measured qd ~ 0 flips from sample to
  // sample; the reference's sign does not (docs/writing_task.md gives the numbers).
  bool friction_from_reference = true;
  // Feed forward the reference's mean acceleration over the sample the torque is held
  // for, (qd_r(k+1) - qd_r(k)) / Ts, instead of its value qdd_r(k) at the sample: the
  // held torque then produces the reference's velocity change even where the path's
  // acceleration jumps in between samples (docs/writing_task.md gives the numbers).
  bool interval_acceleration = false;
  bool saturate = true;       // clamp the command to each joint's effort_limit (where given)
  std::string backend = "analytic";  // the plant's physics (MakeArmBackend)
  ArmBackendOptions backend_options;  // its options: the learned backend's predictor
  // Excitation for recording data to learn from: a seeded Gaussian torque added to the
  // controller's output before clamping, sigma = dither * the joint's effort_limit
  // (1 N·m where none is given), each value held for `dither_hold` samples, so that the
  // torques are not a function of the state alone. 0 = none.
  double dither = 0;
  int dither_hold = 10;             // samples
  std::uint64_t dither_seed = 1;
  // An extra feedforward torque (N x dof, N·m or N; not owned, may be null), row k added
  // to the controller's output at sample k, before the dither and the clamp: the learned
  // signal of iterative learning control (control/iterative_learning.h) or an injected
  // test signal for measuring a closed-loop frequency response. Like every command it
  // reaches the joints the model's delay_samples later. It must have one row per
  // reference sample and one column per joint (RunTrackingTrial checks).
  const Eigen::MatrixXd* feedforward = nullptr;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// The computed-torque gains for `dof` joints: Kp = w^2, Kd = 2 zeta w, w = 2 pi bandwidth.
// Throws std::invalid_argument for a bandwidth or damping that is not positive.
TrackingGains ComputedTorqueGains(int dof, double bandwidth, double damping);

// The PD + feedforward gains: the computed-torque gains scaled by the diagonal of
// M_hat(q0). Throws std::invalid_argument for a bad bandwidth, damping or q0 size.
TrackingGains PdFeedforwardGains(const ArmModel& hat, const Eigen::VectorXd& q0, double bandwidth, double damping);

// The computed-torque law's output (dof, N·m or N) for reference (q_r, qd_r, qdd_r) and
// measured (q, qd), with the friction compensation f_hat evaluated at qd_friction (dof;
// the measured qd, or the reference's); *model_part (if given) gets
// M_hat(q) qdd_r + h_hat(q, qd) + f_hat(qd_friction), the torque the model alone predicts.
Eigen::VectorXd ComputedTorque(const ArmModel& hat, const TrackingGains& gains, bool friction,
                               const Eigen::VectorXd& qd_friction,
                               const Eigen::VectorXd& q_r, const Eigen::VectorXd& qd_r, const Eigen::VectorXd& qdd_r,
                               const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* model_part);

// The PD + feedforward law's output (dof); *model_part (if given) gets the feedforward
// InverseDynamics_hat(q_r, qd_r, qdd_r).
Eigen::VectorXd PdFeedforwardTorque(const ArmModel& hat, const TrackingGains& gains, bool friction,
                                    const Eigen::VectorXd& q_r, const Eigen::VectorXd& qd_r,
                                    const Eigen::VectorXd& qdd_r, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                    Eigen::VectorXd* model_part);

// One tracking run, one row per sample of the reference.
struct TrackingTrial {
  std::string backend, controller;
  double sample_time = 0;        // s
  Eigen::VectorXd t;             // N, s
  Eigen::MatrixXd q, qd;         // N x dof, realised
  Eigen::MatrixXd q_ref;         // N x dof, the reference at the same samples
  Eigen::MatrixXd demand;        // N x dof, N·m: the controller's output before clamping
  Eigen::MatrixXd command;       // N x dof, N·m: sent (clamped to the effort limits when saturate)
  Eigen::MatrixXd model_torque;  // N x dof, N·m: the model-based part of the output
  Eigen::MatrixXd applied;       // N x dof, N·m: the drive torque over [t, t + Ts) (late by the delay)
  // N x dof, N·m: the plant's inverse dynamics (with its friction) over [t, t + Ts),
  // at the interval's mean state with the mean acceleration (qd(t + Ts) - qd(t)) / Ts; a
  // joint below 1e-6 rad/s at both ends sticks, and then its friction is whatever in
  // [-coulomb, coulomb] comes closest to the applied torque. The last row repeats the
  // one before.
  Eigen::MatrixXd needed;
  Eigen::VectorXd error_rms, error_max;         // dof, rad: q_ref - q over the run
  Eigen::VectorXd saturated_fraction;           // dof: share of samples with |demand| >= effort_limit
  Eigen::VectorXd model_vs_command_rms;         // dof, N·m: RMS(command - model_torque)
  Eigen::VectorXd needed_vs_applied_rms;        // dof, N·m: RMS(needed - applied)
  Eigen::VectorXd command_rms;                  // dof, N·m: RMS(command)

  // One line: controller, backend, the worst joint's max error, saturation.
  std::string BriefReport() const;
  // Several lines: every joint's numbers.
  std::string FullReport() const;
};

// Runs `options.controller` with model `hat` on `plant` (simulated on options.backend)
// along `reference`, from rest at its first sample with the model's gravity torque as
// every command before t = 0. Throws InputError for invalid options or an unknown
// backend, std::invalid_argument for a model and plant of different dof, a reference of
// the wrong width or sample time, a feedforward of another shape than the reference's q;
// CheckFailed when the arm runs away.
TrackingTrial RunTrackingTrial(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                               const TrackingOptions& options);

// The same on a backend already built for `plant` (MakeArmBackend or any other
// ArmBackend of the plant's bodies); options.backend is then not used, and the trial's
// backend is the backend's name(). Throws as above, and std::invalid_argument for a
// null backend or one of another arm.
TrackingTrial RunTrackingTrial(const ArmModel& plant, std::unique_ptr<ArmBackend> backend, const ArmModel& hat,
                               const ArmReference& reference, const TrackingOptions& options);

}  // namespace twinsim
