// The predictions a user makes without a model: the yardsticks every model is scored
// beside (identify's and compare's reports; docs/identification.md, "Every horizon").
//
// Both predict row i from what was known K frames earlier (frame S = frame(i) - K), as a
// replay does, and mark the rows they predict; other rows hold the measured pose.
//   - constant velocity: the last two measured poses at or before S, extrapolated at
//     their field-frame velocity to row i's time;
//   - integrated command: the last measured pose at or before S, moved by the commands
//     sent `delay` s before each moment as the robot's body velocity (the kinematics of
//     a robot that does exactly what it is told, late).
#pragma once

#include "analysis/omni_replay.h"
#include "robots/omni/omni_log.h"

namespace twinsim {

OmniReplayResult ConstantVelocityPrediction(const OmniLog& log, int horizon);
OmniReplayResult IntegratedCommandPrediction(const OmniLog& log, int horizon, double delay);

}  // namespace twinsim
