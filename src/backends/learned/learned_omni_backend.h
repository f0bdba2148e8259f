// The learned backend: robots moved one camera frame at a time by a 1-frame predictor
// learned from logs (seed 000, section 4.1), inside the same delay loop as ODE and
// Bullet: it receives the commands when they act on the robot, and the loop shows its
// poses to the behaviour vision_delay frames late.
//
// Its state per robot is the predictor's window: the last `history` poses and the
// commands that acted at those frames. Reset() fills the window with a steady motion at
// the given velocity (commanded as such); MoveBody() replaces the newest pose. With a
// residual predictor each robot also carries the Newtonian model it corrects
// (NominalOmniTrack), stepped with it and moved to every pose it predicts or is given.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "learning/omni_predictor.h"
#include "sim/omni_backend.h"

namespace twinsim {

// Throws InputError when the predictor does not fit a robot's model or the frame rate.
std::unique_ptr<OmniBackend> MakeLearnedOmniBackend(const std::vector<OmniModel>& robots, const FrameTiming& timing,
                                                    std::shared_ptr<const OmniPredictor> predictor);

}  // namespace twinsim
