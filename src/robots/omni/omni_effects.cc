#include "robots/omni/omni_effects.h"

namespace twinsim {

std::vector<std::string> OmniEffects::Active() const {
  std::vector<std::string> names;
  if (time_delay > 0) names.push_back("time_delay");
  if (v_max > 0 || w_max > 0) names.push_back("velocity_saturation");
  if (a_max > 0) names.push_back("traction_limit");
  if (motor_lag > 0) names.push_back("motor_lag");
  if (velocity_scale != 1) names.push_back("velocity_scale");
  if (rotation_drift != 0) names.push_back("rotation_drift");
  return names;
}

}  // namespace twinsim
