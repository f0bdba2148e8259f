// The Open Dynamics Engine (ODE 0.16, double precision) arm backend.
//
// Maximal coordinates: one ODE body per link, at the link's centre of mass with its
// mass and full inertia tensor in the link's axes, joined to its parent (or to the
// fixed world, for the first link) by a dJointTypeHinge about a revolute joint's axis
// or a dJointTypeSlider along a prismatic one. Joint torques go in through
// dJointAddHingeTorque / dJointAddSliderForce; gravity is ODE's. No geoms, so no
// collisions; no motors, limits or friction (the loop adds friction as torques).
// Steps are dWorldStep (the direct solver) of at most ArmEngineOptions::max_step.
// q is read from the joints (hinge angles unwrapped across +-pi). ODE's types stay in
// the .cc.
#pragma once

#include <memory>

#include "engines/arm_engine.h"

namespace twinsim {

// Builds the ODE world for `plant` (already ArmPlantModel() and valid) at q = 0, at rest.
std::unique_ptr<ArmEngine> MakeOdeArmEngine(const ArmModel& plant, const ArmEngineOptions& options);

}  // namespace twinsim
