// The drift of an omni robot's driving noise (driving_noise.drift; `twinsim identify`
// after the noise, docs/identification.md "A run's own drift"): a slow slip beside the
// fast one, what a run's floor, battery or worn wheel adds for seconds and the response
// to the command does not hold. The observer learns it over the frames and carries it
// into every prediction, so it moves the mean a second ahead as well as the intervals.
//
// Its spreads (forward, sideways, turn) and correlation time (3 to 100 s: longer than
// the predictions a behaviour makes) are fitted, the rest of the model held, by the
// observer's predictions half a second and a second ahead over the whole fit logs (from
// every quarter second): each horizon's mean squared position and heading error as a
// share of no drift's, the four averaged (a pattern search in their logarithms). The
// drift is what moves the mean far ahead. Not by the one-frame innovations, which reward
// any freedom to follow the velocity (on a plant whose response the model only resembles
// they asked for a large forward "drift" that predicted a second ahead worse than none),
// nor by the predictions' log density, which took the drift for a way to widen intervals
// that were too narrow, nor by the position alone, which a turn's drift hardly moves
// within a second (docs/identification.md has the numbers). It is kept only where
//   - it takes at least 5 % off that cost, and
//   - the held-out blocks' predictions (the noise's horizons, the noise search's log
//     score) are no worse with it.
// Where the predictions ask for one, its standard errors: the cluster-robust sandwich of
// that cost's residuals over 10 s pieces of the logs (analysis/clustered_standard_errors.h).
//
//   OmniDriftIdentification d = IdentifyDrift(model, stretches, noise_options);
//   if (d.kept) model.driving_noise.drift = d.drift;
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "identification_omni/omni_noise_identification.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

struct OmniDriftIdentification {
  static constexpr double kNotFitted = std::numeric_limits<double>::quiet_NaN();
  bool kept = false;
  OmniDrivingNoise::Drift drift;  // fitted (kept or not); spreads 0 where none was fitted
  // The position RMSE (m) of the predictions 0.5 and 1 s ahead it was fitted on, without
  // and with it (the fit weighs their heading too), and their rows.
  std::array<double, 2> rmse_before{0, 0}, rmse_after{0, 0};
  int rows = 0;
  // The held-out blocks' mean negative log density without and with it (nats per row).
  double held_out_before = 0, held_out_after = 0;
  int held_out_rows = 0;
  int evaluations = 0;
  // Where the predictions asked for it: the standard errors of forward, sideways, turn
  // (m/s, m/s, rad/s) and correlation time (s), cluster-robust over pieces of 10 s of the
  // logs (each of the Robotino's runs one): NaN on a bound or where fewer than two
  // pieces hold predictions, infinite where the logs do not determine it. `bound`: the
  // search's bound each sits on ("lower", "upper"; empty inside).
  std::array<double, 4> standard_error{kNotFitted, kNotFitted, kNotFitted, kNotFitted};
  std::array<std::string, 4> bound;
  std::string note;  // why it was not kept
  std::string on;    // the predictions it was fitted on, in words
};

// Fits the drift of `model` (its response and noise held, its own drift ignored) on the
// fit logs of `stretches` (validation logs left out). Throws InputError for invalid
// options.
OmniDriftIdentification IdentifyDrift(const OmniModel& model, const std::vector<OmniBlockedStretch>& stretches,
                                      const OmniNoiseOptions& options);

// The same on logs each filtered by a model identified without it (`models[i]` on
// `logs[i]`: the left-out logs of `identify --safeguard logs`): the model's own error on a
// run unlike those it was fitted on, taken up as that run's drift, which the observer
// then learns on a new run. Kept where it gains as above (the logs are held out from the
// models already). Throws InputError for invalid options.
OmniDriftIdentification IdentifyDriftOnLeftOutLogs(const std::vector<OmniModel>& models,
                                                   const std::vector<const OmniLog*>& logs,
                                                   const OmniNoiseOptions& options);

}  // namespace twinsim
