// Batch-adaptive estimation of an arm's base parameters (seed 001, section IV-A, as we
// reconstruct it; docs/excitation.md gives the equations and what we followed).
//
// The arm tracks the same periodic excitation q_r(t) trial after trial under PD feedback
// plus a model-based feedforward built from the current estimate beta_k (base inertial
// parameters and friction):
//
//   u = u_ff + u_fb,   u_ff = Y_b(q_r, qd_r, qdd_r) beta_k,   u_fb = Kp e + Kd de/dt,  e = q_r - q.
//
// Whatever torque the model failed to provide, the feedback supplied; so after each
// trial the estimate moves by the least-squares fit of the feedback effort on the
// reference regressor, stacked over the trial's samples:
//
//   beta_{k+1} = beta_k + gamma (Phi' W Phi)^-1 Phi' W U_fb,k
//
// Phi is evaluated along the reference (exact, noise free: no differentiated
// measurements) and the fixed point is the plant's true beta once the tracking error
// vanishes. Converged when ||S (beta_{k+1} - beta_k)|| / ||S beta_{k+1}|| < tolerance,
// S the columns' RMS. The known command delay and the zero-order hold are compensated:
// the command issued at t_k acts over [t_{k+d}, t_{k+d+1}), so its feedforward and its
// regressor row are taken at t_{k+d} + T_s / 2.
//
// The trials run through a narrow function, so that a simulated plant (RunTrial below:
// RK4 on ForwardDynamics of a "plant" ArmModel, with the plant's command delay,
// encoder quantisation and torque noise) can later be swapped for another backend or
// a real arm. The estimator sees only the nominal model and each trial's record.
//
//   ArmTrialOptions plant_options;  plant_options.torque_noise = Eigen::VectorXd::Constant(3, 0.05);
//   BatchAdaptiveResult r = RunBatchAdaptive(nominal, excitation, BatchAdaptiveOptions{},
//                                            SimulatedTrials(plant, plant_options));
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "identification/fourier_trajectory.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

// What the controller runs in one trial: K samples at t_k = k * sample_time.
struct ArmTrialInput {
  double sample_time = 0.001;      // s
  Eigen::MatrixXd q_ref, qd_ref;   // K x n, rad (m) and rad/s (m/s) at t_k
  Eigen::MatrixXd feedforward;     // K x n, N·m or N, issued at t_k
  Eigen::VectorXd hold_command;    // n, N·m or N: issued before t = 0 (holds the arm at q_ref(0))
  Eigen::VectorXd kp;              // n, N·m/rad or N/m
  Eigen::VectorXd kd;              // n, N·m·s/rad or N·s/m
};

// What the controller recorded in one trial.
struct ArmTrial {
  Eigen::MatrixXd q_measured;  // K x n, rad or m, the (quantised) encoder reading at t_k
  Eigen::MatrixXd feedback;    // K x n, N·m or N, u_fb issued at t_k
  Eigen::MatrixXd command;     // K x n, N·m or N, u_ff + u_fb issued at t_k
};

// The simulated plant's imperfections.
struct ArmTrialOptions {
  double encoder_resolution = 0;  // rad or m per count; 0: exact positions
  Eigen::VectorXd torque_noise;   // n, N·m or N, std of white noise added to what each joint receives; empty: none
  int substeps = 1;               // RK4 steps per sample
  std::uint64_t seed = 1;         // of the noise (each trial draws its own stream)

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// Runs one trial on a simulated plant: starts at q_ref(0) with velocity
// qd_ref(0), measures positions at t_k (quantised), computes u_fb from the error and
// its backward difference, and applies the command `plant.delay_samples` samples late,
// held over each sample (plus noise), integrating ForwardDynamics of `plant` by RK4.
// `trial` selects the noise stream. Throws InputError for invalid options,
// std::invalid_argument for inconsistent shapes, CheckFailed when the simulation diverges.
ArmTrial RunTrial(const ArmModel& plant, const ArmTrialInput& input, const ArmTrialOptions& options, int trial = 0);

// Runs one trial (1-based number) and returns what the controller recorded.
using ArmTrialRunner = std::function<ArmTrial(const ArmTrialInput&, int trial)>;

// RunTrial on `plant` for each trial.
ArmTrialRunner SimulatedTrials(const ArmModel& plant, const ArmTrialOptions& options);

struct BatchAdaptiveOptions {
  int max_trials = 10;
  double tolerance = 1e-3;          // relative parameter change that counts as converged
  double learning_gain = 1.0;       // gamma, in (0, 2)
  int periods = 1;                  // periods of the excitation per trial
  double feedback_bandwidth = 10;   // Hz, for the default PD gains
  double feedback_damping = 0.7;    // for the default PD gains
  Eigen::VectorXd kp, kd;           // n each, N·m/rad and N·m·s/rad; empty: Kp = J w^2, Kd = 2 zeta J w with
                                    // J the nominal mass matrix's diagonal averaged over the trajectory
  Eigen::VectorXd joint_weights;    // n, W's diagonal per joint; empty: all 1
  double velocity_threshold = 0.05; // rad/s or m/s: rows of a joint whose reference is slower than this at
                                    // either end of an interval are left out of the fit (the arm may stick)
  Eigen::VectorXd initial;          // r, beta_0; empty: the nominal model's base parameters

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct BatchAdaptiveTrial {
  int trial = 0;                  // 1-based
  Eigen::VectorXd beta_used;      // r, the estimate in the feedforward during this trial
  Eigen::VectorXd beta_next;      // r, the estimate after this trial's update
  Eigen::VectorXd error_rms;      // n, rad or m, q_r - q_measured over the trial
  Eigen::VectorXd error_max;      // n, rad or m
  Eigen::VectorXd feedback_rms;   // n, N·m or N
  double relative_change = 0;     // ||S (beta_next - beta_used)|| / ||S beta_next||
};

struct BatchAdaptiveResult {
  std::string model;
  BaseParameters base;              // of the nominal model
  std::vector<std::string> short_names;  // r, each base parameter's leading standard parameter ("mcx2")
  Eigen::VectorXd scales;           // r, S: column RMS of the stacked reference regressor
  Eigen::VectorXd initial;          // r, beta_0
  Eigen::VectorXd beta;             // r, the final estimate
  Eigen::VectorXd kp, kd;           // n, the gains used
  std::vector<BatchAdaptiveTrial> trials;
  bool converged = false;
  int samples_per_trial = 0;
  int rows_left_out = 0;            // of the fit's (samples - delay) x n rows, for slow reference velocities
  double seconds = 0;               // wall time

  // "converged after 4 trials: parameter change 3.1e-04, tracking error RMS 0.12 -> 0.0021 mrad (joint 2)"
  std::string BriefReport() const;
  // Per trial: change, error and feedback RMS per joint; then the final estimates.
  std::string FullReport() const;
};

// Called after each trial: (trial, max_trials, relative change).
using BatchAdaptiveProgress = std::function<void(int, int, double)>;

// Runs trials until converged or max_trials. Throws InputError for invalid options or
// a trajectory that does not fit the model, std::invalid_argument when `run_trial`
// returns a record of the wrong shape, and whatever `run_trial` throws.
BatchAdaptiveResult RunBatchAdaptive(const ArmModel& model, const FourierTrajectory& trajectory,
                                     const BatchAdaptiveOptions& options, const ArmTrialRunner& run_trial,
                                     const BatchAdaptiveProgress& progress = {});

// One row per trial:
//   trial,<short name 1>..<short name r>,rms1..rmsn,max1..maxn,fb_rms1..fb_rmsn,change
// with the estimate after the trial's update, the tracking error and feedback RMS of
// the trial (rad or m, N·m or N).
std::string FormatBatchAdaptiveCsv(const BatchAdaptiveResult& result);

}  // namespace twinsim
