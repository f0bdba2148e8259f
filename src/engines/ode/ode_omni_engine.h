// The Open Dynamics Engine (ODE 0.16, double precision) implementation of OmniEngine.
//
// Each robot is a chassis body (a cylinder that touches only walls and other chassis)
// carrying one body per wheel on a hinge about the wheel's axle a_i; each wheel touches
// the floor as a sphere with anisotropic Coulomb friction (wheel_friction along the
// rolling direction, roller_friction along the axle). Wheel torques act on the hinges,
// so their reaction tilts and turns the chassis as a real drive train does. All robots
// share one world; the field's walls are static boxes. ODE's own types stay in the .cc.
#pragma once

#include <memory>
#include <vector>

#include "engines/omni_engine.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// Builds an ODE world holding `robots` (each already Finalize()d) on `field`, robot i
// standing still at a default place; call SetState to put it where it should be.
// Throws std::invalid_argument when a model has no derived fields or fewer than 3 wheels.
std::unique_ptr<OmniEngine> MakeOdeOmniEngine(const std::vector<OmniModel>& robots,
                                              const FieldModel& field);

}  // namespace twinsim
