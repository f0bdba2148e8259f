// The Open Dynamics Engine (ODE 0.16, double precision) implementation of BallEngine: a
// sphere against the floor plane, the walls (static boxes) and every robot's chassis (a
// kinematic convex prism: the cylinder cut by the flat front). Friction is Coulomb
// along the slip at each contact; bounces are ODE's restitution. ODE's types stay in
// the .cc.
#pragma once

#include <memory>
#include <vector>

#include "engines/ball_engine.h"

namespace twinsim {

// Builds an ODE ball world for `robots` on `field`, the ball at rest on the floor at
// the centre. Throws std::invalid_argument for a ball model that is not valid.
std::unique_ptr<BallEngine> MakeOdeBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots,
                                              const FieldModel& field);

}  // namespace twinsim
