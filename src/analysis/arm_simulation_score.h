// What a simulator of an arm is for: predicting its motion from its torques. An arm
// model is scored on a log by simulating it open loop from the logged torques (sent as
// commands: the model's delays, effects and friction applied by the Newtonian backend),
// started from the logged state, against the logged positions (docs/identification.md,
// "Simulation error"):
//
//   - windows of `horizon` seconds, each restarted from the logged q and q̇ of its first
//     row with the commands logged before it in the delay line; every row of every
//     window is scored (the error grows along a window);
//   - the free run: one window over the whole log, as the nonlinear system-identification
//     benchmarks score a simulator (fit = 100 (1 - ||q - q_sim|| / ||q - mean q||)).
//
// Beside the model, two baselines a user would try with no model at all: the joints held
// where the window starts, and moved on at the velocity they had there. A model that
// does not beat them at a horizon predicts nothing there.
//
// The simulation steps at the log's own period (the model's sample_time replaced by it,
// its delay_samples rescaled to the nearest whole row): logs sampled slower than the
// controller (the KUKA's 200 Hz) hold each torque over a row, as their rows record it.
//
//   ArmSimulationScore s = ScoreArmSimulation(model, log, {});
//   std::printf("%s", FormatArmSimulationScores({{"identified", s}}).c_str());
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "backends/arm_backend_factory.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

class ArmSimulation;

// The open-loop simulation of `sim`'s model from row `start` of `log`: reset to the
// logged q and q̇ there, with the commands logged in the delay_samples rows before it
// in flight, then driven by the logged torques, one row per sample; the simulated q at
// rows start+1 .. start+steps into *q (steps x dof). A run-away (CheckFailed) propagates,
// or with `hold_on_runaway` holds the last good state for the remaining rows and returns
// false. Throws std::invalid_argument when the window does not fit the log.
bool SimulateArmFromLog(ArmSimulation* sim, const ArmLog& log, int start, int steps, Eigen::MatrixXd* q,
                        bool hold_on_runaway = false);
// The same from the state (q0, qd0) at row `start` instead of the logged one (a shooting
// segment's own initial state); the state it ends in is sim->backend()'s.
bool SimulateArmFromState(ArmSimulation* sim, const ArmLog& log, int start, int steps, const Eigen::VectorXd& q0,
                          const Eigen::VectorXd& qd0, Eigen::MatrixXd* q, bool hold_on_runaway = false);

// `model` stepping once per row of a log sampled every `period` s: its sample_time
// replaced by the period, its delay_samples rescaled to the nearest whole row.
ArmModel ArmModelAtLogPeriod(const ArmModel& model, double period);

// The first rows of the windows of `horizon` s (0: one window over the whole log) that a
// score of `model` (at the log's period) simulates on `log`, each *length rows long: the
// rows between the log's edge_samples, after the model's delay, one window after the
// other. With `scored` (horizon > 0 only), only windows whose rows start .. start +
// length all pass it, each the first that fits after the one before. Empty when none fits.
std::vector<int> ArmSimulationWindows(const ArmModel& model, const ArmLog& log, double horizon, int* length,
                                      const std::function<bool(int row)>& scored = {});

// The constant-velocity baseline at row start + ahead: the joints moved on from row
// `start` at the q̇ logged there (ahead rows of the log's period).
Eigen::RowVectorXd ConstantVelocityQ(const ArmLog& log, int start, int ahead);

struct ArmSimulationScoreOptions {
  // s: the windows' lengths; 0 is the free run over the whole log.
  std::vector<double> horizons = {0.1, 1.0, 0};
  std::string backend = "analytic";  // the backend that simulates the model (MakeArmBackend's names)
  ArmBackendOptions backend_options;  // e.g. the learned backend's predictor
  // Horizons longer than the log's usable rows are left out instead of refused (a log
  // too short for any window then gets no horizons).
  bool drop_long_horizons = false;
  // Rows a window may score (e.g. a diagnosis's test rows); empty: every row. A window
  // lies wholly in such rows (ArmSimulationWindows); not with the free run (horizon 0).
  std::function<bool(int row)> scored_rows;
  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// One horizon's errors, per joint (rad or m), pooled over the rows of every window.
struct ArmHorizonScore {
  double horizon = 0;      // s; 0: the free run
  int windows = 0;         // windows simulated
  int rows = 0;            // rows scored (every window's rows after its first)
  int diverged = 0;        // windows the model ran away in (their rows held at the last good state)
  // Windows in which a simulated joint left its range (its limits, widened to what the
  // log itself reached), which a real arm's end stops do not let it: the model is wrong
  // there, whatever its RMSE says. Their rows are scored as simulated (holding them
  // would score a model that leaves early as well as holding still); a window that also
  // ran away counts in both.
  int left_range = 0;
  int left_range_joint = -1;  // 0-based: the joint of the first window that left (-1: none)
  int left_range_row = -1;    // the log's row where it was first seen outside
  double left_range_t = 0;    // s: that row's time
  double left_range_q = 0;    // rad or m: its simulated position there
  double left_range_limit = 0;  // rad or m: the bound it passed
  Eigen::VectorXd rmse;    // the model's position error
  Eigen::VectorXd fit;     // percent: 100 (1 - ||error|| / ||q - mean q||) over the scored rows;
                           // NaN for a joint that never moves (an empty cell in the CSV)
  Eigen::VectorXd hold;    // the baseline that holds the window's first q
  Eigen::VectorXd constant_velocity;  // the baseline that moves on at the window's first q̇
};

struct ArmSimulationScore {
  std::string path;  // the log's
  std::vector<ArmHorizonScore> horizons;  // in the order of the options
  // The free run's simulated q (when horizon 0 was scored): row r is the log's row
  // free_run_start + 1 + r (rows x dof, rad or m); empty otherwise.
  int free_run_start = -1;
  Eigen::MatrixXd free_run;
};

// Scores `model` on `log` (the rows between its edge_samples, where logged or derived
// q̇ is reliable). Throws InputError for invalid options, a log of another arm, or one
// too short for a window (without drop_long_horizons).
ArmSimulationScore ScoreArmSimulation(const ArmModel& model, const ArmLog& log,
                                      const ArmSimulationScoreOptions& options = {});

// A table per log of the named models' scores: one row per horizon and joint, the
// models' RMSE and fit beside the two baselines'. All scores of one log must share its
// horizons.
std::string FormatArmSimulationScores(const std::vector<std::pair<std::string, ArmSimulationScore>>& scores);

// simulation.csv: log,model,horizon,joint,windows,rows,diverged,rmse,fit,rmse_hold,
// rmse_constant_velocity,left_range (rad or m; fit in percent, empty for a joint that
// never moves; horizon 0: the free run; left_range: the windows that left a joint's
// range, ArmHorizonScore::left_range).
std::string FormatArmSimulationScoresCsv(const std::vector<std::pair<std::string, ArmSimulationScore>>& scores);

}  // namespace twinsim
