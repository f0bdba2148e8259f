// The ILC tests' linear plant: one link on a vertical axis (a turntable: gravity does
// nothing), no friction, J = 0.01 + 2 * 0.3^2 = 0.19 kg m^2, one sample of command
// delay, under PD + feedforward without friction compensation.
#pragma once

#include "control/computed_torque.h"
#include "robots/arm/arm_model.h"

namespace twinsim::testing {

constexpr double kTurntableInertia = 0.19;  // kg m^2

inline ArmModel Turntable() {
  return LoadArmModelFromYamlString(
      "robot: arm\nname: one\nsample_time: 0.001\ndelay_samples: 1\ndh: modified\njoints:\n"
      "  - name: hinge\n    type: revolute\n    a: 0\n    alpha_deg: 0\n    d: 0\n    theta_deg: 0\n"
      "    effort_limit: 100\n    link:\n      mass: 2.0\n      com: [0.3, 0, 0]\n"
      "      inertia: [0.001, 0.01, 0.01, 0, 0, 0]\n",
      "turntable.yaml");
}

inline TrackingOptions TurntablePd() {
  TrackingOptions o;
  o.controller = TrackingController::kPdFeedforward;
  o.friction = false;
  return o;
}

}  // namespace twinsim::testing
