// Identification of an arm by output error: the parameters a simulator needs, fitted to
// the motion the logged torques make rather than to the torques a logged motion needs
// (docs/identification.md, "Output error"; issue 41).
//
// Starting from a model (usually identify's inverse-dynamics estimate), it minimises the
// simulation error of ScoreArmSimulation's windows (arm_simulation_score.h) on the
// fitting logs: every row of every window of `horizon` seconds, simulated open loop from
// the logged state by the logged torques, each joint's error divided by the error of
// the constant-velocity baseline on the same rows; beside it the torque error on every
// row (PredictArmCommands), each joint's divided by the start's, times `torque_weight`:
// a simulation error bought with torques the arm never logged is not a better model.
// Every fourth window is held out of the fit; the refined model is kept only when those
// windows are simulated better (their squared errors over the baseline's, summed over
// the joints), else the start is returned as it was. Per joint it refines
//   - the moving link's inertial scale k (mass, first moment and inertia times k: a
//     physically consistent link stays consistent),
//   - the nominal viscous and Coulomb friction (kept positive),
//   - with `offsets`, the torque_offset effect's tau0,
//   - with `stribeck`, a second fit: the stribeck_friction effect's break-away s - c and
//     speed vs (a Coulomb level that holds near zero speed), kept only where it beats the
//     plain refinement on the held-out windows; with `presliding` the same with
//     bristles (stribeck_friction's sigma0, sigma1, maxwell) fitted beside them,
// by Levenberg-Marquardt (Ceres) with central differences at a fixed step in
// coordinates (ln k, the frictions' logarithms, the offset in tenths of the joint's
// torque RMS; ArmFitCoordinates), the Jacobian's columns simulated on `threads` threads
// (deterministic: each column on its own simulation).
//
// With `whole_run` the windows are the logs themselves (issue 65): the simulation error
// of each log's free run from its first state, as the system-identification benchmarks
// score a simulator, fitted by multiple shooting. Each log's first three quarters are cut
// into segments of `segment` seconds, each simulated from a state of its own (a fitted
// coordinate, starting at the logged one), the end of one tied to the start of the next
// by a continuity residual weighted kContinuity times a row's; the parameters are then
// those of one continuous run, found without integrating a drift over the whole log
// from the first iteration. No torque rows: the last quarter of every log, simulated
// free from its first logged state, is the check the refinement must pass.
//
// Either way the summary carries the fit's standard errors, with the windows' stretches
// of the logs (or the segments) as independent clusters (analysis/fit_covariance.h): a
// simulated error runs smooth from row to row, so rows are not independent measurements.
//
//   ArmOutputErrorSummary summary;
//   ArmModel refined = RefineArmByOutputError(identified, logs, {}, &summary);
//   std::printf("%s", summary.FullReport().c_str());
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "analysis/arm_fit_coordinates.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

struct ArmOutputErrorOptions {
  double horizon = 0.1;       // s: the simulated windows' length (> 0; not used with whole_run)
  // s: windows of these lengths fitted at once beside `horizon`'s (each set weighted to
  // start near 1 per joint, so every horizon counts alike), and held out by the longest
  // set's every fourth window: a shorter window is held out where it lies wholly inside
  // one of those, and neither fitted nor held out where it crosses one's edge. The
  // summary's RMSE is `horizon`'s windows'; the keep decisions sum every set's held-out
  // cost. Empty: `horizon` alone.
  std::vector<double> also_horizons;
  bool whole_run = false;     // fit each log's free run by multiple shooting instead of windows
  double segment = 2.0;       // s: whole_run's shooting segments (> 0)
  int max_iterations = 30;    // Levenberg-Marquardt iterations
  bool offsets = false;       // also refine each joint's torque_offset tau0
  // Also try friction that holds at low speed: per joint a break-away above the Coulomb
  // level that fades with speed (stribeck_friction: its s - c and vs), fitted after the
  // plain refinement from where it ended (not tried when that refinement is not kept),
  // and kept only where it removes at least 10 % of the held-out windows' cost left by
  // the plain refinement.
  bool stribeck = false;
  // With stribeck: the low-speed fit's Stribeck friction acts through bristles (LuGre's,
  // or a Maxwell-slip element) whose stiffness sigma0 is fitted per joint too (sigma1
  // critically damping them against the joint's inertia; ArmFitCoordinates).
  ArmPresliding presliding = ArmPresliding::kNone;
  double torque_weight = 1;   // the torque rows' weight beside the simulated rows' (0: none)
  // The torque rows at rest are left out as the identification leaves them out
  // (WlsIdentificationOptions::rest_share, ArmRestRows): this share of a joint's RMS speed.
  double rest_share = 0.02;
  std::string backend = "analytic";
  int threads = 0;            // 0: one per core
  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct ArmOutputErrorSummary {
  double horizon = 0;
  std::vector<double> also_horizons;  // the windows fitted beside `horizon`'s (ArmOutputErrorOptions)
  // With whole_run: the segments' length and count, the windows then being the logs'
  // fitted three quarters and held-out quarters simulated free; each joint's spread of
  // q about its mean there (fit = 100 (1 - RMSE / spread)); the largest continuity
  // defect left between segments, in q over the joint's spread.
  bool whole_run = false;
  double segment = 0;
  int segments = 0;
  Eigen::VectorXd spread_fit, spread_check;
  double largest_defect = 0;
  int iterations = 0;
  int fit_windows = 0, check_windows = 0;   // over all logs: fitted, and held out (every fourth)
  bool kept = false;                        // the held-out windows got better: the refined model returned
  Eigen::VectorXd rmse_before, rmse_after;  // per joint, rad or m: the fit windows' position RMSE
  Eigen::VectorXd check_before, check_after;  // the same on the held-out windows
  Eigen::VectorXd constant_velocity;          // per joint: the baseline's RMSE on the fit windows
  Eigen::VectorXd scale;                      // per joint: the link's inertial scale k found
  Eigen::VectorXd viscous_before, viscous_after, coulomb_before, coulomb_after;
  Eigen::VectorXd offset_before, offset_after;  // tau0 (unchanged when offsets are not refined)
  // With ArmOutputErrorOptions::stribeck and a kept plain refinement (stribeck_tried):
  // the plain refinement's held-out RMSE, whether
  // the low-speed friction beat it (and was returned), and its break-away s - c (N·m or
  // N) and speed vs (rad/s or m/s) per joint as fitted.
  bool stribeck_tried = false, stribeck_kept = false;
  Eigen::VectorXd check_plain, breakaway, stribeck_velocity;
  Eigen::VectorXd bristle_stiffness;  // with presliding: sigma0 per joint as fitted, else empty
  std::vector<std::string> at_bound;  // coordinates that ended at the edge of their range ("scale of joint 1", ...)
  std::vector<std::string> low_speed_at_bound;  // the low-speed fit's, kept or not ("break-away of joint 1", ...)
  // The returned fit's standard errors (analysis/fit_covariance.h: each stretch of a log
  // as long as a window, or each shooting segment, an independent cluster), joints by
  // coordinate blocks in ArmFitCoordinates' order, each block of the kind in
  // standard_error_kinds: a share of the value for scales and frictions, N·m or N for an
  // offset; NaN at a bound, infinite where the logs do not determine it. Empty when
  // nothing was fitted.
  Eigen::MatrixXd standard_error;
  std::vector<ArmFitCoordinates::Kind> standard_error_kinds;
  // A table: per joint the simulation errors before and after (and the baseline's), the
  // scale, frictions and offsets found, their standard errors; what ended at a bound;
  // whether it was kept.
  std::string FullReport() const;
};

// "0.1", "0.1 and 1", "0.1, 0.5 and 1": a stage's window lengths in seconds, as %g prints them.
std::string OutputErrorWindowLengths(double horizon, const std::vector<double>& also);

// output_error.csv: stage,joint,coordinate,value,standard_error, a row per stage (1, 2, ...
// of a continuation), joint and fitted coordinate (ArmFitCoordinates::Key: scale,
// viscous, coulomb, offset, breakaway, stribeck_velocity, bristle_stiffness); the value
// as fitted (kept or not) and its standard error in the same unit, empty at a bound,
// inf where the logs do not determine it.
std::string FormatArmOutputErrorCsv(const std::vector<ArmOutputErrorSummary>& stages);

// What the fit sees at `model` before its first step: each joint's position error over
// the fit windows simulated from the logged states, over the constant-velocity
// baseline's, squared and summed over the joints; with whole_run, over the shooting
// segments simulated from their logged states, each joint's over its spread of q. The
// frictions are raised to their floors as the fit starts them. Lower is a better start;
// comparable between models on the same logs and options. Throws as
// RefineArmByOutputError.
double ArmOutputErrorStartCost(const ArmModel& model, const std::vector<ArmLog>& logs,
                               const ArmOutputErrorOptions& options);

// Refines `start` on `logs` (joint counts checked): the refined model, or `start` when
// the held-out windows do not get better. Throws InputError for invalid options or logs
// too short for four windows.
ArmModel RefineArmByOutputError(const ArmModel& start, const std::vector<ArmLog>& logs,
                                const ArmOutputErrorOptions& options, ArmOutputErrorSummary* summary = nullptr);

}  // namespace twinsim
