// The wheel motors of an omni robot, seen at the wheel (gear included).
//
// A voltage-limited DC motor can give at most the torque on its torque-speed line:
// tau in [-stall - k w, stall - k w] with k = stall / no_load_speed, so it cannot push
// past its no-load speed but brakes harder the faster it turns against the command.
// The bearing's viscous loss acts on top. Both the ODE/Bullet backends and the analytic
// model use this one function.
#pragma once

#include <algorithm>

#include "robots/omni/omni_model.h"

namespace twinsim {

// Net torque on wheel `wheel` (N·m) for a commanded torque (N·m) at wheel speed w
// (rad/s). A weaker motor (OmniModel::motor_strength) has its whole torque-speed line
// scaled: less stall torque, the same no-load speed.
inline double WheelMotorTorque(const OmniModel& model, int wheel, double commanded, double w) {
  const double stall = model.motor_stall_torque * model.MotorStrength(wheel);
  const double back_emf = stall / model.motor_no_load_speed * w;
  const double available = std::clamp(commanded, -stall - back_emf, stall - back_emf);
  return available - model.bearing_damping * w;
}

}  // namespace twinsim
