// The omni effect vocabulary of CONTRACT.md: behaviour a real robot has and the
// Newtonian model lacks. Switched on per model file (`effects:`, docs/models.md), used
// by the plants that stand in for real robots, and named by the diagnosis workflow.
//
// Every effect acts where it would on a real robot, above the physics engine, so it
// works identically on ODE, Bullet and the analytic model:
//   time_delay          commands reach the firmware `delay` s later (sub-frame resolution)
//   velocity_saturation the firmware clips commands to v_max (m/s) and w_max (rad/s)
//   motor_lag           the command is followed through a first-order lag of `time_constant` s
//   traction_limit      the body's horizontal force is limited to m * a_max: acceleration
//                       beyond a_max (m/s^2) is lost to slip
//   velocity_scale      the firmware's wheel radius is wrong: the robot moves `scale` times
//                       as fast as commanded
//   rotation_drift      the robot turns at `rate` rad per metre travelled while translating
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace twinsim {

struct OmniEffects {
  double time_delay = 0;      // s; 0 = off
  double v_max = 0;           // m/s; 0 = off (velocity_saturation)
  double w_max = 0;           // rad/s; 0 = off (velocity_saturation)
  double motor_lag = 0;       // s, time constant; 0 = off
  double a_max = 0;           // m/s^2; 0 = off (traction_limit)
  double velocity_scale = 1;  // 1 = off
  double rotation_drift = 0;  // rad/m; 0 = off

  // Names (contract vocabulary) of the effects that are on.
  std::vector<std::string> Active() const;
  bool any() const { return !Active().empty(); }
};

// The omni effect vocabulary (CONTRACT.md), in its order.
const std::vector<std::string>& OmniEffectNames();

// The parameter keys of an omni effect (model-file keys; empty for an unknown name).
std::vector<std::string> OmniEffectParameters(const std::string& name);

// Sets effect `name` with `parameters` (model-file keys, SI units) on `effects`,
// replacing its earlier values. Throws InputError for an unknown name or key (listing
// the known ones), a missing value, or a value outside the model file's range.
void SetOmniEffect(const std::string& name, const std::map<std::string, double>& parameters, OmniEffects* effects);

// The effects that are on, in the vocabulary's order, with their parameters.
std::vector<std::pair<std::string, std::map<std::string, double>>> ListOmniEffects(const OmniEffects& effects);

}  // namespace twinsim
