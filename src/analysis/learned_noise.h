// The learned backend's own driving noise (issue 42): what a learned predictor does not
// predict, as a Gauss-Markov slip per robot axis (OmniDrivingNoise: three spreads and a
// correlation time), chosen so that the learned backend's sampled rollouts are
// calibrated on rows the predictor was not trained on.
//
// The one-step residual of a predictor is the wrong target: its inputs (the last frames)
// already carry the slip's correlation, and the camera's noise is mixed in. So the noise
// is fitted the way it is used. From every `stride`-th frame of the held-out logs
// (after the tracker's warm-up) `samples` rollouts of the learned backend run K frames
// ahead, each moved on by its own draw of the slip (analysis/omni_replay.h, the
// tracker's samples); their covariance about the prediction, plus the camera's, is the
// predictive distribution of the measured pose. The cost is its mean negative log
// density at each horizon (4, 16 and 63 frames), averaged over the horizons; a pattern
// search (core/pattern_search.h) over the logarithms of the spreads and the correlation
// time minimises it under common random numbers (the same draws for every candidate).
// The calibration at the end (analysis/omni_calibration.h) is on the rows it was fitted
// on; a log the predictor never saw (`compare`) is the judge.
//
//   LearnedNoiseFit fit = FitLearnedDrivingNoise(model, predictor, held_out_logs, {});
//   OmniPredictor p = *predictor;
//   p.SetDrivingNoise(fit.noise);
//   p.Save(path);
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "analysis/omni_interval_scale.h"
#include "learning/omni_predictor.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

struct LearnedNoiseOptions {
  std::vector<int> horizons{4, 16, 63};  // frames
  int samples = 16;                      // rollouts per start
  int stride = 4;                        // frames between starts at least
  // The fit's starts over all logs at most: the stride grows on long logs (a fit's cost is
  // starts x samples x the longest horizon per evaluation, so a long log at every 4th
  // frame took minutes for a neural predictor; docs/benchmarks.md).
  int max_starts = 150;
  std::uint64_t seed = 1;                // of the rollouts' draws
  int max_evaluations = 90;              // of the cost, besides the start's; the growths get half as many more
  // Each rollout draws the predictor's weights from their own uncertainty first, where it
  // carries one (OmniReplayOptions::parameter_draws): the noise is then fitted as what
  // the weights' uncertainty leaves.
  bool parameter_draws = true;
};

struct LearnedNoiseFit {
  OmniDrivingNoise noise;                    // simulated: true
  OmniDrivingNoise start;                    // where the search began
  std::vector<OmniCalibration> calibration;  // per horizon, on the rows fitted
  double cost_before = 0, cost_after = 0;    // nats per row, averaged over the horizons
  int rows = 0;                              // predicted rows scored, over the horizons
  int evaluations = 0;
};

// True when some log of `logs` is long enough for a prediction at the longest horizon
// (after the tracker's warm-up): FitLearnedDrivingNoise has rows to fit on.
bool LongEnoughForLearnedNoise(const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options = {});

// Fits the driving noise of `predictor` (a one-frame one) on the learned backend over
// `logs` (held out from its training). Throws InputError when the logs give no
// predictions at the longest horizon.
LearnedNoiseFit FitLearnedDrivingNoise(const OmniModel& model, const OmniPredictor& predictor,
                                       const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options = {},
                                       const std::function<void(int, int)>& progress = {});

// The safeguard of the learned backend's intervals (docs/learning.md, "The intervals'
// safeguard"): `predictor` (its driving noise fitted, its own scales ignored) predicts
// `logs` (the same held-out rows) at SafeguardHorizons(options.horizons), and
// SafeguardFromFolds keeps a conformal scale of the rollouts' spread per horizon and part
// where each fold, scaled as the other says, comes nearer 90 % in its 90 % regions
// without a worse log density. The folds: alternate logs where each fold so gets
// kSafeguardLeastRows rows at every horizon, else each log's earlier and later half of
// its starts. The rollouts draw afresh (another seed than the noise's search), but the
// rows are those the noise was fitted on: the check across folds is not independent of
// the noise's fit, as identify's crossed noise is (a finding, docs/learning.md).
OmniIntervalSafeguard FitLearnedIntervalSafeguard(const OmniModel& model, const OmniPredictor& predictor,
                                                  const std::vector<OmniLog>& logs, const LearnedNoiseOptions& options = {});

// The calibration of the learned backend with `predictor` (and its driving noise) on
// `log` at each horizon, from `samples` rollouts per start at every `stride`-th frame
// (max_starts does not apply; `compare`); the constant spread is fitted on the same rows
// (a baseline with hindsight). With `by_turn_rate`, the same rows by quarter of their
// measured turn rate (CalibrateRowsByTurnRate); with `by_distance` and a predictor that
// knows its training inputs' ranges, by how far beyond them each prediction's inputs
// went (CalibrateRowsByDistance over OmniBackend::TakeInputExcess: below 0.25 of the
// ranges' span the learned backend counts a step as seen; empty otherwise).
std::vector<OmniCalibration> CalibrateLearnedOmniLog(const OmniModel& model, const OmniPredictor& predictor,
                                                     const OmniLog& log, const LearnedNoiseOptions& options = {},
                                                     std::vector<std::array<OmniTurnQuarter, 4>>* by_turn_rate = nullptr,
                                                     std::vector<OmniDistanceCalibration>* by_distance = nullptr);

// One line per horizon: coverage of the 50 % and 90 % ellipses, energy score against
// the constant spread.
std::string FormatLearnedNoiseFit(const LearnedNoiseFit& fit);

}  // namespace twinsim
