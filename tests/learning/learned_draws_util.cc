#include "learning/learned_draws_util.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "test_util.h"

namespace twinsim::testing {

OmniReplayOptions QuietLearnedReplay(OmniPredictor predictor, int horizon, int samples, int stride) {
  OmniDrivingNoise quiet;
  quiet.sd = {1e-9, 1e-9, 1e-9};
  quiet.correlation_time = 0.05;
  quiet.simulated = true;
  predictor.SetDrivingNoise(quiet);
  OmniReplayOptions o;
  o.backend = "learned";
  o.backend_options.predictor = std::make_shared<const OmniPredictor>(std::move(predictor));
  o.horizon = horizon;
  o.samples = samples;
  o.stride = stride;
  return o;
}

DrawnSpread SpreadWithAndWithoutDraws(const OmniLog& log, OmniReplayOptions options, OmniReplayResult* drawn) {
  options.parameter_draws = true;
  const OmniReplayResult with = ReplayOmniLog(Omni4(), log, options);
  options.parameter_draws = false;
  const OmniReplayResult without = ReplayOmniLog(Omni4(), log, options);
  DrawnSpread out;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!with.predicted[i] || with.samples[i].empty()) continue;
    out.moved_predictions += with.pose[i].x != without.pose[i].x || with.pose[i].y != without.pose[i].y;
    out.drawn += with.covariance[i].topLeftCorner<2, 2>().trace();
    out.fixed += without.covariance[i].topLeftCorner<2, 2>().trace();
    ++out.rows;
  }
  out.drawn = std::sqrt(out.drawn / std::max(out.rows, 1));
  out.fixed = std::sqrt(out.fixed / std::max(out.rows, 1));
  if (drawn) *drawn = with;
  return out;
}

}  // namespace twinsim::testing
