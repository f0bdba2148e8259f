// The diagnosis workflow (`twinsim diagnose`, CONTRACT.md): find where a model and
// measured logs disagree, name the missing effects from the contract's vocabulary,
// add them to the model with fitted parameters, show the gap shrink on data that chose
// nothing, and say what is left unexplained. One method for both robots
// (docs/diagnose.md):
//
//   1. Find: replay the nominal model over the logs (arm: the commands its inverse
//      dynamics needs; omni: the 4-frame prediction of `replay`) and describe the
//      residual per joint or axis (over time, against velocity, near reversals, its
//      lag against the command, its spectrum) and the noise floor the data allow.
//   2. Name: every effect of the vocabulary is a candidate; each is fitted on the fit
//      blocks of the logs and scored on the selection blocks.
//   3. Add: forward selection with Holm-corrected long-run t tests, an information
//      gain that counts parameters, and a backward step (forward_selection.h).
//   4. Say what is left: on the test blocks, whiteness, cross-correlation with the
//      inputs and a learned residual beside the physics (ChannelAdequacy).
//   5. Show: a DiagnosisReport, written as report.json, report.html and model.yaml
//      (diagnosis_report.h).
//
// This header holds what both robots share: options, the split of the logs into fit,
// selection and test blocks, and the report's plain structs (the tests are in
// statistics.h). The robots' own halves are arm_diagnosis.h and omni_diagnosis.h.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "analysis/held_out_blocks.h"
#include "diagnosis/statistics.h"
#include "signal/series_statistics.h"

namespace twinsim {

// No bound: the diagnosis's searches start from it.
inline constexpr double kInf = std::numeric_limits<double>::infinity();

struct DiagnosisOptions {
  double held_out = 0.4;      // share of each log's time blocks held out from every fit (half selection, half test)
  double block_seconds = 0;   // s, length of a time block; 0 = automatic (a 20th of the log, 0.5 to 10 s)
  int max_effects = 3;        // the most effects added
  // An effect is added only when it lowers the selection rows' mean squared error by at
  // least this share of it (a floor against effects too small to matter) ...
  double min_improvement = 0.05;
  // ... the reduction is significant: a one-sided t test with a long-run (Newey-West)
  // standard error, Holm-corrected over the round's candidates at family-wise level
  // `alpha`, or a reduction of at least a quarter on fit and selection rows alike ...
  double alpha = 0.05;
  // ... and it earns its parameters: n_eff ln(MSE before / MSE after) > 2 k, with n_eff
  // the selection rows' effective count and k the effect's parameters (docs/diagnose.md).
  // Omni: the physics that replays the model; "" = the engine it was fitted on
  // (OmniModel::fitted_on), else analytic.
  std::string backend;
  int horizon = 4;                   // omni: frames predicted ahead (the contract's replay K)
  // Arm: rad/s (m/s) below which a joint counts as standing still, where its friction
  // is anything up to the static level (stiction) rather than the friction law's value.
  double standstill = 0.02;
  int threads = 0;                   // 0 = one per core; results do not depend on it
  // Refit the model's own parameters on the fit blocks before adding effects (arm:
  // twinsim identify's weighted least squares of the base inertial parameters and
  // friction; omni: identification of the delay, per-axis response and couplings). Off
  // by default: a trusted arm model keeps a payload named `payload` instead of hidden in
  // re-identified link inertias.
  bool refit_model = false;
  // Check what is left on the test rows (whiteness, cross-correlation, a learned
  // residual beside both models: ChannelAdequacy, LearnedYardstick). Off only where the
  // gaps alone are wanted (a plant's own gap in a test).
  bool check_adequacy = true;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// One candidate effect as it was tried: its fitted parameters and scores.
struct DiagnosisCandidate {
  int round = 0;                             // selection round, 1-based
  std::string name;                          // contract vocabulary
  int joint = -1;                            // 0-based; -1 for whole-robot effects
  std::map<std::string, double> parameters;  // model-file keys, SI units
  double fit_gap = 0;                        // metric on the fit rows with it added
  double held_out_gap = 0;                   // metric on the held-out rows with it added
  // share of the round's selection-row MSE it removed (of its joint's, for an effect on
  // one arm joint: DiagnosisProblem::ChannelOf)
  double reduction = 0;
  double t_statistic = 0;                    // of that reduction (long-run standard error)
  double p_value = 1;                        // one-sided, before the Holm correction
  bool significant = false;                  // after the Holm correction over the round
  double information_gain = 0;               // n_eff ln(MSE before / after) - 2 k, on the same rows; > 0 to be added
  // Selection blocks whose squared error it changed, and of those the ones it lowered:
  // the 25 % rule (a large share removed, significant or not) asks for most of them.
  int blocks_changed = 0, blocks_improved = 0;
  // A test that fits nothing (DiagnosisProblem::StateTest), where the problem has one
  // for it: its two-sided p (NaN: none) and its finding in words.
  double state_p_value = std::numeric_limits<double>::quiet_NaN();
  std::string state_test;
  bool selected = false;
  std::string harm;                          // the joint or axis it makes significantly worse, if any: not added
  std::string veto;                          // passed on the selection rows but made the test rows worse: not added
  std::string note;                          // why it could not be fitted, when it could not
};

// An effect the diagnosis added, as report.json lists it.
struct DiagnosedEffect {
  std::string name;
  int joint = -1;                            // 0-based; -1 for whole-robot effects (null)
  std::map<std::string, double> parameters;  // after the final joint refit
  // One standard error per parameter (the fit's covariance, scaled by the residual's
  // variance and correlation length); NaN where the logs do not determine it.
  std::map<std::string, double> standard_errors;
  double gap_reduction = 0;                  // share of the test rows' gap it removes on top of the effects before it
  std::string evidence;                      // one sentence: what decided it
};

// The "find" step for one joint (arm) or axis (omni: forward, sideways, rotation).
struct ChannelFinding {
  std::string channel;           // "joint 2", "forward", ...
  std::string unit;              // of the residual: "N m", "m", ...
  double rms = 0;                // of the nominal model's residual, held-out and fit rows
  double rms_after = 0;          // of the repaired model's residual
  double rms_near_reversal = 0;  // within 0.1 s of a velocity reversal or stop
  double rms_moving = 0;         // elsewhere
  double velocity_correlation = 0;      // of the residual with the velocity
  double acceleration_correlation = 0;  // ... with the acceleration
  double lag = 0;                // s, the shift that best aligns the measured command (or motion) with the model's
  double dominant_frequency = 0; // Hz, the residual spectrum's peak
  double noise = 0;              // the noise floor's share on this channel (same unit)
};

// Series for the report's plots, per channel.
struct ChannelSeries {
  std::vector<double> t;          // s, subsampled for plotting
  std::vector<double> before;     // residual of the nominal model
  std::vector<double> after;      // residual of the repaired model
  std::vector<double> velocity;   // of the joint or axis, same rows
  std::vector<double> frequency;  // Hz
  std::vector<double> psd_before, psd_after;  // unit^2/Hz
};

// A path for the report's side-by-side plot (omni, seed 000 Fig. 4 style).
struct DiagnosisPath {
  std::string name;
  std::vector<double> t, x, y, theta;  // s, m, m, rad
};

// The repaired model's residual on the test rows, per channel: is what is left noise?
struct ChannelAdequacy {
  std::string channel;
  double rms = 0;                        // of the repaired model's residual on the test rows
  double noise = 0;                      // the noise floor's share on this channel
  std::vector<double> autocorrelation;   // lags 1.. (in steps of `step` rows)
  double step_seconds = 0;               // s between the lags
  double whiteness_bound = 0;            // 95 % band of a white residual's autocorrelation
  double whiteness_p = 1;                // Ljung-Box: small means the residual is not white
  std::vector<CrossCorrelation> inputs;  // the residual against each input, largest first
  // The learned yardstick on this channel: the repaired model's test-row RMS with a
  // learned residual correction (trained on the fit rows), and the test of that drop.
  double learned_rms = 0;
  double learned_reduction = 0;          // share of the squared residual the correction removed
  double learned_p = 1;                  // one-sided, long-run standard error
  // Where the unexplained part lies: the band (Hz) that holds most of the learned
  // correction's power.
  double band_low = 0, band_high = 0;
  // The test RMS stands more than the problem's FloorRatio times the noise above it.
  bool above_floor = false;
  // The learned correction's drop counts: significant after Holm's correction over the
  // channels, at least the minimum improvement, and at least the problem's LearnedFloor()
  // times the noise in RMS.
  bool learned_significant = false;
  // Something is left that is not noise: a significant predictable part (the learned
  // residual, lowering the RMS by at least the problem's LearnedFloor() times the
  // noise), or a residual far above the floor (docs/diagnose.md).
  bool unexplained = false;
};

// Beside the physics: a learned residual predictor trained on the fit rows, scored on
// the same test rows (docs/diagnose.md, "The learned yardstick").
struct LearnedYardstick {
  std::string learner;                   // what was trained, in words; or why none could be
  // False when no learned residual could be trained or replayed (learner says why): then
  // no channel's "predictable" is known, and the report says so instead of "nothing".
  bool available = false;
  double nominal = 0;                    // the test-row gap of the nominal model plus the learned correction
  double repaired = 0;                   // ... of the repaired model plus the learned correction
  // Share of the predictable gap the named physics explains: (nominal^2 - repaired^2) /
  // (nominal^2 - best^2), best the lowest of the four gaps; NaN when nothing is predictable.
  double physics_share = 0;
};

// Omni: every predictor's test-row error at one horizon (analysis/omni_horizons.h).
struct DiagnosisHorizon {
  std::string label;          // "4 frames", "0.25 s", "1 s", "3 s"
  double seconds = 0;
  int rows = 0;               // test rows scored
  // given model, [identified model,] repaired model, constant velocity, integrated command
  // [, linear predictor: the seed's, trained on the fit rows]
  std::vector<std::string> predictors;
  std::vector<double> gaps;   // the report's metric (m), one per predictor
};

// Arm: the given and the repaired model simulated open loop from the logs' torques in
// windows of `seconds` lying wholly in test rows (analysis/arm_simulation_score.h),
// pooled over the logs; beside them the constant-velocity baseline on the same windows.
struct DiagnosisSimulation {
  double seconds = 0;
  int windows = 0;
  int rows = 0;
  std::vector<double> nominal, repaired, constant_velocity;  // per joint: position RMSE, rad or m
};

// One change found in a log, for report.json's `changes` and the verdict.
struct ResponseChange {
  std::string log;       // the path as given
  double t = 0;          // s, the log's own clock
  std::string quantity;  // "velocity scale" or "turn-rate scale"
  double before = 0, after = 0;
  double t_stat = 0;
  std::string what;      // one sentence: "the velocity scale fell from 0.67 to 0.34 at t = 4.2 s"
};

struct DiagnosisReport {
  std::string robot;                    // "omni" or "arm"
  std::string model_name;
  std::string metric;                   // what the gaps measure, with its unit
  double gap_before = 0;                // metric of the nominal model on the test rows
  double gap_after = 0;                 // ... of the repaired model
  double noise_floor = 0;               // the metric a perfect model would reach, estimated from the data
  // Omni: where the wander drawn from the model's driving noise gave a floor above the
  // model's own error on the fit rows beyond their scatter (the floor is then held at
  // that error, `noise_floor`), the floor drawn and that error (the metric's unit); else 0.
  double drawn_floor = 0, own_fit_error = 0;
  double fit_gap_before = 0, fit_gap_after = 0;  // the same on the fit rows
  double selection_gap_before = 0, selection_gap_after = 0;  // ... on the selection rows
  // Residual rows of each kind: fit, selection (chose the effects), test (report the
  // gaps); held_out_rows = selection + test. Guard rows between blocks of different
  // kinds belong to none.
  int fit_rows = 0, held_out_rows = 0, selection_rows = 0, test_rows = 0;
  double guard_seconds = 0;
  double alpha = 0.05;                  // the options the selection ran with, for the method text
  double min_improvement = 0.05;
  int max_effects = 3;
  double floor_ratio = 0;    // the problem's FloorRatio() and LearnedFloor(), for the method text
  double learned_floor = 0;
  LearnedYardstick yardstick;
  std::vector<ChannelAdequacy> adequacy;  // one per channel
  std::vector<std::string> removed;      // effects the backward step took out again, with why
  double held_out_share = 0;
  double block_seconds = 0;
  std::vector<std::string> logs;
  std::vector<DiagnosedEffect> effects;
  std::vector<DiagnosisCandidate> candidates;
  std::vector<ChannelFinding> findings;
  std::vector<ChannelSeries> series;    // one per finding
  std::vector<DiagnosisPath> paths;    // omni: measured, nominal and repaired over one held-out stretch
  std::vector<std::string> notes;       // what the user should know (skipped candidates, limits)
  // Where the response changes part way through a log (CONTRACT.md's `changes`): omni
  // robots (response_changes.h); arms are not searched and list none.
  std::vector<ResponseChange> changes;
  // Where the written model predicts worse than the given one anywhere (omni: a horizon of
  // the test rows), one sentence with the numbers: said first in the verdict.
  std::string caution;
  // Omni: the test-row gap at the report's horizon, 0.25 s, 1 s and 3 s (rows whose
  // prediction ends on a test row, started wherever); empty for arms.
  std::vector<DiagnosisHorizon> horizons;
  // Arm: the simulation error on the test rows at 0.1 s and 0.5 s (those the test blocks
  // hold a window of); empty for omni robots.
  std::vector<DiagnosisSimulation> simulation;
  // With DiagnosisOptions::refit_model: the held-out gap of the refitted model before any
  // effect (gap_before stays the given model's); NaN when not refitted.
  double refit_gap = std::numeric_limits<double>::quiet_NaN();
  double seconds = 0;                   // s, wall time
};

// ---- Shared machinery (used by arm_diagnosis.cc and omni_diagnosis.cc) ----

// One channel's residual rows over every log, for its ChannelFinding.
struct ChannelSamples {
  std::vector<double> before, after;            // residual of the nominal and the repaired model
  std::vector<double> velocity, acceleration;   // of the joint or axis, the rows of `before`
  std::vector<double> near_reversal, moving;    // `before` split by closeness to a reversal or stop
};

// Sets f's RMS values, correlations and dominant frequency (the peak of s.psd_before).
void DescribeChannel(const ChannelSamples& x, const ChannelSeries& s, ChannelFinding* f);

// Which rows of a channel lie near a reversal or a stop, the events where friction and
// delays show: times (ascending) within `window` s of a row where the velocity changes
// sign or stands (|v| below `stand` times its largest |v|). Ask in ascending time.
class ReversalWindows {
 public:
  ReversalWindows(const std::vector<double>& t, const std::vector<double>& v, double stand, double window);
  bool Near(double t);

 private:
  std::vector<double> times_;
  double window_;
  std::size_t next_ = 0;
};

// The residual spectra's Welch segment for n rows: a quarter of them rounded down to a
// power of two, 8 at least and `cap` at most.
int WelchSegmentFor(std::size_t n, int cap);

// Fills s's spectra of the nominal and the repaired model's residuals (`before`,
// `after`) at `rate` Hz with WelchSegmentFor(before.size(), cap).
void ResidualSpectra(const std::vector<double>& before, const std::vector<double>& after, double rate, int cap,
                     ChannelSeries* s);

// Root mean square of v (0 when empty).
double Rms(const std::vector<double>& v);

// "0.12", "1.5e-05": a parameter as the report prints it.
std::string FormatParameter(double value);
// "viscous_friction (joint 2)" or "traction_limit".
std::string EffectLabel(const std::string& name, int joint);

}  // namespace twinsim
