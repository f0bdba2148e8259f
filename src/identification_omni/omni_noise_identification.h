// The driving noise identified for predictions ahead and for the simulation (`twinsim
// identify` with an omni model, after the parameters; docs/identification.md, "The
// driving noise").
//
// The prediction-error fit (omni_identification.h) tunes the filter's noise for the
// best 4-frame mean: it says how much to trust the camera, not how far the robot
// wanders. A simulator that draws the noise (driving_noise.simulated) and intervals
// around a prediction need the wander's own size and duration. So, with the
// identified response held, the noise's spreads (forward, sideways, turn), its
// correlation time, the scale of the model's process noise and the camera's noise
// (position and heading, observer.measurement_noise_*) are identified by the
// Gaussian likelihood of the predictions 4, 16 and 63 frames ahead (analysis/
// omni_calibration.h, MeanLogScore): the observer's predictive distribution must hold
// the measured poses at every horizon a behaviour looks ahead. The rows are the
// held-out blocks', which the response was not fitted on: on the fit blocks the
// response follows the blocks' own wander a little, and a noise fitted there came out
// too narrow on unseen minutes (issue 42; the coverage measured is in
// docs/identification.md). A pattern search in the logarithms of the seven
// (doubling steps, halved in log until 5 %), the spreads taken at the logs' typical
// motion (OmniTypicalMotion); then again with the spreads' growth with the robot's
// speed, acceleration and turn rate (driving_noise.per_speed, per_acceleration,
// per_turn_rate; in log(1 + g)). The choices are made out of sample for the noise as
// well: the same two searches on each half of the held-out blocks (every other block),
// each half's noise scored on the other half. The growth is kept only where it scores
// the other halves better than none, the noise only where it scores them better than the
// prediction-error fit's (validation logs never choose: they only report the
// calibration). The calibration and the intervals' safeguard then predict each half with
// the other's noise refitted under the whole fit's growths (OmniCrossedNoise). Standard
// errors: the sandwich of the cost's Hessian and the held-out blocks' gradients (blocks
// are nearly independent, rows within one are not).
//
//   std::vector<OmniBlockedStretch> stretches = ...;  // identification's blocks
//   OmniNoiseIdentification n = IdentifyDrivingNoise(model, stretches, options);
//   if (n.kept) model = n.model;
#pragma once

#include <array>
#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "analysis/omni_interval_scale.h"
#include "analysis/omni_spread_budget.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// A stretch of a log in identification's blocks: rows from score_from on are scored,
// each in a fit or a held-out block (held), with the block's number (unique across logs).
struct OmniBlockedStretch {
  const OmniLog* log = nullptr;
  std::size_t score_from = 0;
  const std::vector<char>* held = nullptr;   // per row
  const std::vector<int>* block = nullptr;   // per row
  bool validation = false;                   // a wholly held-out log
};

// True where row i's prediction both ends and starts (`horizon` frames earlier) in
// blocks of the given kind, after the stretch's lead-in: a fit row's prediction never
// starts from an estimate corrected to a held-out measurement, and a held-out row's never
// from a fit one.
bool ScoredInBlocks(const OmniBlockedStretch& s, std::size_t i, bool held_out, int horizon);

struct OmniNoiseOptions {
  std::string backend = "analytic";
  std::vector<int> horizons{4, 16, 63};  // frames; the longest is predicted, the rest on the way
  // The fit predicts from every stride-th frame of the held-out blocks: every 8th left
  // the 90 % ellipses narrower on unseen minutes than every 4th (issue 42; the coverage
  // of each in docs/identification.md).
  int stride = 4;
  int score_stride = 2;      // the calibration from every score_stride-th
  double max_delay = 0.35;   // s: rows start after the longest warm-up a replay can have
  // Of the likelihood, per search (without and with growth, on all and on each half; half
  // of it for each half's refit under the whole fit's growths).
  int max_evaluations = 150;
  // A search moves only where the log likelihood of the average horizon's rows gains
  // more than this (nats; 0: every gain, as until 2026-12-07). 0.5 stopped the searches
  // short on a ridge (docs/identification.md, "The driving noise for predictions ahead").
  double resolution_nats = 0.1;
  int threads = 0;           // 0 = one per core; results do not depend on it
  // The validation logs' calibration with the parameters' own uncertainty too
  // (OmniReplayOptions::parameter_shifts, on `backend`), as `compare` reports it; the
  // held-out blocks' (the noise's fit and its checks) without.
  std::vector<std::array<OmniModel, 2>> parameter_shifts;

  bool IsValid(std::string* why) const;
};

// One of the ten, as identify's report lists it.
struct OmniNoiseParameter {
  // "forward", "sideways", "turn", "correlation_time", "process_noise_scale", "camera_xy",
  // "camera_theta", "per_speed", "per_acceleration", "per_turn_rate"
  std::string name;
  std::string unit;         // "m/s", "rad/s", "s", "x", "m", "rad", "1/(m/s)", "1/(m/s^2)", "1/(rad/s)"
  double start = 0;         // the prediction-error fit's value (spreads: standing still)
  double value = 0;         // identified
  double standard_error = 0;  // NaN where the blocks do not determine it
  // "lower" or "upper" where the identified value sits on the search's bound (the logs ask
  // for less, or more, than it allows: the camera's noise has a floor, the observer's
  // kMinMeasurementNoise*); empty inside. A growth at none is not on a bound.
  std::string bound;
};

// The noise fitted on one half of the held-out blocks, for the other half's calibration:
// where a growth was kept, with the growths held at the whole fit's (a half's own, on
// half the rows, stray far from them: to the bounds on a minute's log).
struct OmniCrossedNoise {
  OmniModel model;       // the given model with the half's noise
  std::set<int> blocks;  // the half's blocks
};

struct OmniNoiseIdentification {
  OmniModel model;       // the given model with the noise identified where kept, else the given model
  bool kept = false;     // each half of the held-out blocks scored the other half's noise better
  std::vector<OmniNoiseParameter> parameters;
  // Mean negative log density over the horizons (nats per row): on the held-out blocks it
  // was fitted on (fit_*); and each half's noise on the other half, averaged (held_out_*:
  // out of sample for the noise and the response).
  double fit_before = 0, fit_after = 0;
  double held_out_before = 0, held_out_after = 0;
  int fit_rows = 0, held_out_rows = 0;  // summed over the horizons (the same rows)
  std::array<OmniCrossedNoise, 2> crossed;  // where kept
  int evaluations = 0;
  std::string note;
  std::string growth_note;  // why no growth with speed and acceleration was kept, where one was fitted
};

// Identifies the noise of `model` (its response held) on `stretches`. Throws
// InputError for invalid options or stretches without fit rows.
OmniNoiseIdentification IdentifyDrivingNoise(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                             const OmniNoiseOptions& options);

// The mean negative log density (nats per row, averaged over options.horizons that have
// rows) of `model`'s predictions on the held-out blocks of `stretches`, the noise
// search's cost; *rows (where given) the rows it is over. Infinite where none, or where
// the filter diverged.
double HeldOutLogScore(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                       const OmniNoiseOptions& options, int* rows = nullptr);

// The calibration of `model` at each of options.horizons on the validation logs where
// there are any, else on the held-out blocks, its constant-spread baseline fitted on the
// fit rows. With `crossed` (a noise fitted on the held-out blocks), the held-out blocks of
// each half are scored with the other half's noise, never with one fitted on them. With
// `by_distance` and validation logs, the same rows split by how far each prediction's
// inputs lie from the fit blocks' (SeenInputsOfFitBlocks; kCalibrationDistances; each
// range's baseline fitted on its rows): where the intervals can be relied on; `model`'s
// interval_scale must then grow with no distance (its seen inputs are replaced). With
// `by_turn_rate`, the same rows by quarter of their measured turn rate
// (CalibrateRowsByTurnRate). With `budget` and no validation logs, the spread budget of
// the same held-out rows per horizon, pooled (analysis/omni_spread_budget.h; each half
// with the other half's noise, as the calibration; the scale left at 1); with validation
// logs it is left empty.
std::vector<OmniCalibration> CalibrateOnBlocks(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                               const OmniNoiseOptions& options,
                                               const std::array<OmniCrossedNoise, 2>* crossed = nullptr,
                                               std::vector<OmniDistanceCalibration>* by_distance = nullptr,
                                               std::vector<std::array<OmniTurnQuarter, 4>>* by_turn_rate = nullptr,
                                               std::vector<OmniSpreadBudget>* budget = nullptr);

// The seen inputs (robots/omni/omni_seen_inputs.h) of `model` on the fit blocks of
// `stretches` (validation logs left out): each fit row's frame as the observer saw it.
OmniSeenInputs SeenInputsOfFitBlocks(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                     const OmniNoiseOptions& options);

// Fits the safeguard of `model` (its own interval_scale ignored) on the held-out blocks'
// rows in their two halves (the folds), with `crossed` each half predicted with the
// noise fitted on the other; at options.horizons and between them
// (SafeguardHorizons). Throws as CalibrateOnBlocks.
OmniIntervalSafeguard FitIntervalSafeguard(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                           const OmniNoiseOptions& options,
                                           const std::array<OmniCrossedNoise, 2>* crossed = nullptr);

}  // namespace twinsim
