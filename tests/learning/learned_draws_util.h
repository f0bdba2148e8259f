// Shared by the tests of a learned predictor's own uncertainty (a linear one's weights'
// directions, a network's ensemble).
#pragma once

#include "analysis/omni_replay.h"
#include "learning/omni_predictor.h"

namespace twinsim::testing {

// Sampled replay options for the learned backend running `predictor` with its driving
// noise all but off (1e-9), so that the samples spread by the draws of its parameters
// alone; `horizon` frames ahead, `samples` rollouts from every `stride`-th frame.
OmniReplayOptions QuietLearnedReplay(OmniPredictor predictor, int horizon, int samples, int stride);

// `log` replayed with `options` on omni4, with the parameters' draws and without: the
// samples' RMS position spread about the prediction (m) each way, over the rows with
// samples, and how many of those rows' predictions differ between the two (none: the
// draws leave the prediction alone). *drawn (optional) gets the replay with the draws.
struct DrawnSpread {
  double drawn = 0, fixed = 0;
  int rows = 0, moved_predictions = 0;
};
DrawnSpread SpreadWithAndWithoutDraws(const OmniLog& log, OmniReplayOptions options, OmniReplayResult* drawn = nullptr);

}  // namespace twinsim::testing
