// Identification of an omni robot from its own logs (`twinsim identify` with an omni
// model; docs/identification.md, "The omni robot").
//
// A model written from a data sheet gets the robot's response to its commands wrong:
// the delay, how much of each command the robot reaches and how fast, what a sideways
// command does to the heading. Identification estimates those as physical parameters
// of the model file, so that every engine (analytic, ODE, Bullet) runs the result:
//   - the total delay from command to observed pose, in time (whole frames in `delay:`,
//     the rest as the `time_delay` effect; shorter or longer than the model's);
//   - per axis (forward, sideways, turn): the share of the command reached
//     (velocity_scale), the set-point's ramp (controller.*.slew_rate), a first-order lag
//     beyond the controller's (motor_lag), and the speed limits (velocity_saturation)
//     where the log reaches them;
//   - the couplings between axes: turn per forward and per sideways command
//     (turn_coupling), forward and sideways leaking into each other (cross_coupling).
// The score is the contract's replay: each frame predicted from the measured state
// `horizon` frames earlier, estimated by the model's own Kalman filter
// (estimation/omni_observer.h). The parameters, the delay and the filter's driving noise
// among them, minimise the prediction error on the fit blocks of the logs (the
// prediction-error method; Ceres, numeric derivatives through the engine, after a
// profile search of the delay). The held-out blocks, whose predictions neither start
// nor end in a fit block, give the gaps, beside the constant-velocity extrapolation of
// the measured poses (no model at all) and the identified model through the open-loop
// tracker.
//
//   OmniIdentificationOptions options;
//   OmniModel identified;
//   OmniIdentificationReport report = IdentifyOmni(nominal, logs, options, &identified);
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "identification_omni/omni_drift_identification.h"
#include "identification_omni/omni_noise_identification.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// Where identify fits the intervals' safeguard (OmniIdentificationOptions::safeguard); the
// words --safeguard takes, in this order: blocks, logs, off.
enum class OmniSafeguard { kBlocks, kLogs, kOff };
inline constexpr const char* kOmniSafeguardWords[] = {"blocks", "logs", "off"};

struct OmniIdentificationOptions {
  std::string backend = "analytic";  // the physics that replays the model
  int horizon = 4;                   // frames predicted ahead (the contract's replay K)
  // How each prediction's start state is estimated (analysis/omni_replay.h): the model's
  // Kalman filter (kObserver), whose driving noise (driving_noise:) is fitted with the rest
  // (the prediction-error method); or the open-loop response with corrected poses (kTracker).
  OmniReplayState state = OmniReplayState::kObserver;
  double held_out = 0.3;             // share of each log's time blocks held out from the fit
  double block_seconds = 0;          // s; 0 = automatic (a 20th of the longest log, 0.5 to 10 s)
  int stride = 4;                    // the fit predicts from every stride-th frame
  int max_iterations = 20;           // Ceres iterations per solve
  double max_delay = 0.35;           // s, the longest total delay searched
  int threads = 0;                   // 0 = one per core; results do not depend on it
  // With the observer's state: the driving noise identified anew for predictions ahead
  // (omni_noise_identification.h), kept where the held-out blocks score it better.
  bool noise = true;
  // With the noise: its drift (a slow slip, driving_noise.drift) fitted on the
  // predictions 0.5 and 1 s ahead (omni_drift_identification.h), kept where it takes 5 %
  // off them and the held-out blocks are no worse.
  bool drift = true;
  // A three-wheel robot's turn by the direction it drives in (turn_coupling's third_sin
  // and third_cos), tried where the fit logs drive in enough directions and kept where
  // the held-out blocks' poses ask for it.
  bool turn_harmonics = true;
  // With the observer's state, the intervals' safeguard (analysis/omni_interval_scale.h)
  // fitted on: kBlocks, the two halves of the held-out blocks; kLogs, each fit log
  // predicted by the model identified on the others (identification once more per log;
  // at least two logs); kOff, none.
  OmniSafeguard safeguard = OmniSafeguard::kBlocks;
  // Keep the fit's seen inputs (observer.seen_inputs) in the model even where no scale
  // grows with them (the left-out-logs safeguard's folds measure distances from them).
  bool keep_seen_inputs = false;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// One estimated parameter, as report.json lists it.
struct IdentifiedParameter {
  std::string name;     // "forward.gain", "delay", ...
  std::string key;      // where it lives in the model file ("effects.velocity_scale.forward", ...)
  std::string unit;     // "s", "m/s^2", "" for ratios
  std::string meaning;  // one sentence
  double nominal = 0;   // the given model's value
  double value = 0;     // the estimate
  // One standard error (the fit's covariance, scaled by the residual's variance and its
  // correlation length); NaN where the log does not determine the parameter.
  double standard_error = std::numeric_limits<double>::quiet_NaN();
  // False: not estimated (see note). Then value is the model's for an axis the logs do
  // not excite; 0 (none) for a limit, lag or ramp the data does not ask for; else the
  // fit's value at the edge of its range.
  bool estimated = true;
  // True: fitted, but the logs cannot tell it from others (see note): held at the fit's
  // value while the others' standard errors are taken, and has none itself.
  bool held = false;
  std::string note;       // why not estimated, or what limits it
};

// Held-out prediction error of one predictor, per axis and in all.
struct OmniGap {
  std::string name;    // "nominal model", "identified model", "constant velocity"
  double rmse = 0;     // m, position error of the `horizon`-frame prediction
  double pose = 0;     // m, sqrt(dx^2 + dy^2 + (r dtheta)^2), the diagnosis's metric
  double forward = 0, sideways = 0, turn = 0;  // m, RMS per axis (turn: r dtheta)
};

// Every predictor's held-out error at one horizon, over the same rows.
struct OmniHorizonGaps {
  std::string label;   // "4 frames", "0.25 s", "1 s", "3 s"
  int frames = 0;      // K
  double seconds = 0;  // K frame periods
  int rows = 0;        // rows scored
  // nominal model, identified model, constant velocity, integrated command (the command
  // as the body velocity, at the identified delay)
  std::vector<OmniGap> gaps;
};

// One stretch for the report's plots: measured body velocity against command, nominal
// and identified, per axis.
struct OmniIdentificationSeries {
  std::string log;
  std::vector<double> t;  // s
  std::vector<std::array<double, 3>> command, measured, nominal, identified;  // forward, sideways, turn
};

struct OmniIdentificationReport {
  std::string model_name;
  std::vector<std::string> logs;
  std::vector<std::string> validation_logs;  // wholly held out
  std::string backend;
  int horizon = 4;
  double frame_period = 0;    // s
  double block_seconds = 0;   // s
  double held_out_share = 0;
  int fit_rows = 0, held_out_rows = 0;
  std::vector<IdentifiedParameter> parameters;
  // On the held-out blocks (and the validation logs): nominal, identified, constant velocity.
  std::vector<OmniGap> held_out;
  std::vector<OmniGap> validation;  // empty without validation logs
  // The prediction error at the report's horizon, 0.25 s, 1 s and 3 s (free runs from the
  // estimated state) on `horizons_on`: the validation logs when given, else the held-out
  // blocks, counting rows whose prediction ends there, wherever it starts.
  std::vector<OmniHorizonGaps> horizons;
  std::string horizons_on;
  double fit_cost_nominal = 0, fit_cost_identified = 0;  // m, RMS of the fit residual
  double noise_floor = 0;     // m, the pose metric a perfect model reaches (camera noise)
  // The collinearity index of the parameters estimated with standard errors (1: their
  // effects independent; identification/identifiability.h); those it would push above 20 are
  // held at the fit's value, each with a note naming what it trades with.
  double collinearity = 1;
  std::vector<double> delay_profile_s, delay_profile_rms;  // s, m: the fit error against the delay
  int solver_iterations = 0;
  int evaluations = 0;        // replays of the fit blocks
  // The driving noise for predictions ahead (with the observer's state and options.noise).
  bool noise_identified = false;
  OmniNoiseIdentification noise;
  // The noise's drift (with options.drift).
  bool drift_identified = false;
  OmniDriftIdentification drift;
  // The identified model's predictive distribution on the held-out blocks (or the
  // validation logs) at 4, 16 and 63 frames (analysis/omni_calibration.h).
  std::vector<OmniCalibration> calibration;
  // With validation logs, the same split by how far the predictions' inputs lie from the
  // fit blocks' (analysis/omni_calibration.h, kCalibrationDistances).
  std::vector<OmniDistanceCalibration> calibration_by_distance;
  // The same by quarter of the log's turn rate over each prediction, per horizon
  // (analysis/omni_calibration.h, CalibrateRowsByTurnRate).
  std::vector<std::array<OmniTurnQuarter, 4>> calibration_by_turn_rate;
  // Where the predicted position spread comes from, per horizon of the calibration
  // (analysis/omni_spread_budget.h): on the validation logs, pooled, where there are
  // any; else on the calibration's held-out rows (each half with the other half's noise
  // where the noise was fitted on them); `spread_budget_on` says which.
  std::vector<OmniSpreadBudget> spread_budget;
  std::string spread_budget_on;
  // The intervals' safeguard fitted after it (its scales in the model's observer where
  // kept); the calibration above is the covariance's before it.
  OmniIntervalSafeguard safeguard;
  std::vector<std::string> notes;
  std::vector<OmniIdentificationSeries> series;
  double seconds = 0;

  const OmniGap* Gap(const std::vector<OmniGap>& gaps, const std::string& name) const;
};

// Identifies `nominal` on `logs` (fit and held-out blocks) and scores it on `validation`
// (wholly held out; may be empty). *identified receives the model. Throws InputError for
// invalid options, logs of different frame rates or too short to hold blocks out;
// CheckFailed when the model diverges at the start.
OmniIdentificationReport IdentifyOmni(const OmniModel& nominal, const std::vector<OmniLog>& logs,
                                      const std::vector<OmniLog>& validation, const OmniIdentificationOptions& options,
                                      OmniModel* identified,
                                      const std::function<void(int, int, const std::string&)>& progress = {});

// The held-out gap of `model` on the rows IdentifyOmni scores with `options` (the same
// blocks and rows for any model): a plant's own gap, or a second model's. `radius` (m)
// weighs the heading error (the nominal model's chassis radius in IdentifyOmni).
// Throws as IdentifyOmni.
OmniGap OmniHeldOutGap(const OmniModel& model, const std::vector<OmniLog>& logs, const OmniIdentificationOptions& options,
                       const std::string& name, double radius);

// The model moved one standard deviation either way along each principal direction of
// its observer.parameter_covariance (identify's parameters), in identify's coordinates
// so that every parameter stays in its range: pairs {plus, minus}, the widest direction
// first; directions under 1e-9 of the widest's variance left out. Replayed beside the
// model, half their predictions' difference is a direction's share of the spread the
// parameters make (OmniReplayOptions::parameter_shifts). None without a covariance. A
// limit the model has off (a speed limit or ramp of 0) is left out with its rows.
// Throws InputError (naming the model's file) for a parameter identify does not fit.
std::vector<std::array<OmniModel, 2>> ParameterShiftedModels(const OmniModel& model, double frame_period);

// The report as JSON, a plain-text table, and a self-contained HTML page.
std::string FormatOmniIdentificationJson(const OmniIdentificationReport& report);
std::string FormatOmniIdentificationTable(const OmniIdentificationReport& report);
class Renderer;
std::string FormatOmniIdentificationHtml(const OmniIdentificationReport& report, Renderer& renderer);

}  // namespace twinsim
