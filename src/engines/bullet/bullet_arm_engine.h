// The Bullet (3.24, double precision) arm backend: a Featherstone btMultiBody.
//
// Reduced coordinates: a fixed base and one link per joint, revolute or prismatic, so
// the joints cannot come apart and q is Bullet's own joint position. Bullet wants each
// link's frame at its centre of mass along the principal axes of its inertia, so each
// link's inertia tensor is diagonalised and the joint axes and offsets are written in
// those axes. Joint torques go in through addJointTorque; gravity is the world's. No
// colliders, no damping (Bullet's default 0.04 is set to 0), no limits or motors.
// Steps are Bullet's RK4 multibody steps (useRK4Integration) of at most
// ArmEngineOptions::max_step.
// Bullet's types stay in the .cc.
#pragma once

#include <memory>

#include "engines/arm_engine.h"

namespace twinsim {

// Builds the multibody for `plant` (already ArmPlantModel() and valid) at q = 0, at rest.
std::unique_ptr<ArmEngine> MakeBulletArmEngine(const ArmModel& plant, const ArmEngineOptions& options);

}  // namespace twinsim
