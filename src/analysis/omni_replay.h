// Replaying a measured omni log through a model (`twinsim replay`, CONTRACT.md).
//
// Row i of the result is the model's prediction of frame i made from the measured
// state K frames earlier and the logged commands since, delayed by the model's command
// + vision delay D: the step from frame j to j+1 is driven by the command logged at
// frame j - D. K = 0 is one free run from the first row.
//
// The state at the start frame S = i - K: the measured pose at S. Velocity and the
// on-board controller's state (set-points, integrals) are not measured; they come from
// running the model over the up to kWarmUpFrames (0.5 s at 30 fps) frames before S,
// started from the measurement there (pose, velocity by a backward difference). So vision noise enters
// through poses only, as it does for a learned predictor that sees the last frames.
// Rows without enough history (no row at S, or commands older than the log) hold the
// measured pose.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "io/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

inline constexpr int kWarmUpFrames = 15;

struct OmniReplayOptions {
  std::string backend = "ode";
  int horizon = 4;  // K, frames; 0 = free run

  // Returns an empty string when valid, else what is wrong.
  std::string Validate() const;
};

struct OmniReplayResult {
  std::vector<double> t;             // s, one per log row
  std::vector<Pose2> pose;           // predicted (or held measured) pose per row
  std::vector<bool> predicted;       // false where the measured pose was held
  int delay_frames = 0;              // D used
  int num_predicted() const;
};

// Root-mean-square distance (m) between the predicted rows and the log's poses.
double PositionRmse(const OmniLog& log, const OmniReplayResult& result);

// Throws InputError for an unknown backend; CheckFailed if the model diverges.
OmniReplayResult ReplayOmniLog(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                               const std::function<void(int, int)>& progress = {});

}  // namespace twinsim
