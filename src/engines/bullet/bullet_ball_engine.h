// The Bullet (3.24, float64) implementation of BallEngine: a sphere against the floor
// plane, the walls (static boxes) and every robot's chassis (a kinematic convex hull:
// the cylinder cut by the flat front). Bullet's friction is Coulomb along the slip;
// friction and restitution combine as products, so the ball carries 1 and each surface
// the ball model's coefficient for it. Bullet's types stay in the .cc.
#pragma once

#include <memory>
#include <vector>

#include "engines/ball_engine.h"

namespace twinsim {

// Builds a Bullet ball world for `robots` on `field`, the ball at rest on the floor at
// the centre. Throws std::invalid_argument for a ball model that is not valid.
std::unique_ptr<BallEngine> MakeBulletBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots,
                                                 const FieldModel& field);

}  // namespace twinsim
