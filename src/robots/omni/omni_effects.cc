#include "robots/omni/omni_effects.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/error.h"

namespace twinsim {

std::vector<std::string> OmniEffects::Active() const {
  std::vector<std::string> names;
  if (time_delay > 0) names.push_back("time_delay");
  if (v_max > 0 || w_max > 0) names.push_back("velocity_saturation");
  if (a_max > 0) names.push_back("traction_limit");
  if (motor_lag > 0 || axis_lag[0] > 0 || axis_lag[1] > 0 || axis_lag[2] > 0) names.push_back("motor_lag");
  if (velocity_scale != 1 || axis_scale != std::array<double, 3>{1, 1, 1}) names.push_back("velocity_scale");
  if (rotation_drift != 0) names.push_back("rotation_drift");
  if (turn_per_forward != 0 || turn_per_sideways != 0) names.push_back("turn_coupling");
  if (sideways_per_forward != 0 || forward_per_sideways != 0) names.push_back("cross_coupling");
  return names;
}


const std::vector<std::string>& OmniEffectNames() {
  static const std::vector<std::string> names = {"time_delay",     "velocity_saturation", "traction_limit",
                                                 "motor_lag",      "velocity_scale",      "rotation_drift",
                                                 "turn_coupling",  "cross_coupling"};
  return names;
}

std::vector<std::string> OmniEffectParameters(const std::string& name) {
  if (name == "time_delay") return {"delay"};
  if (name == "velocity_saturation") return {"v_max", "w_max"};
  if (name == "traction_limit") return {"a_max"};
  if (name == "motor_lag") return {"time_constant", "forward", "sideways", "turn", "braking", "field_frame"};
  if (name == "velocity_scale") return {"scale", "forward", "sideways", "turn"};
  if (name == "rotation_drift") return {"rate"};
  if (name == "turn_coupling") return {"forward", "sideways"};
  if (name == "cross_coupling") return {"sideways_per_forward", "forward_per_sideways"};
  return {};
}

void SetOmniEffect(const std::string& name, const std::map<std::string, double>& parameters, OmniEffects* effects) {
  const std::vector<std::string> keys = OmniEffectParameters(name);
  if (keys.empty()) {
    std::string known;
    for (const auto& n : OmniEffectNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown omni effect '" + name + "' (known: " + known + ")");
  }
  std::string known;
  for (const auto& k : keys) known += (known.empty() ? "" : ", ") + k;
  for (const auto& [key, value] : parameters) {
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
      throw InputError("effect '" + name + "': unknown parameter '" + key + "' (known: " + known + ")");
    }
    if (!std::isfinite(value)) throw InputError("effect '" + name + "': '" + key + "' is not a finite number");
  }
  auto get = [&](const std::string& key, double lo, double hi, bool lo_open) {
    auto it = parameters.find(key);
    if (it == parameters.end()) throw InputError("effect '" + name + "': missing parameter '" + key + "'");
    const double v = it->second;
    if (v < lo || v > hi || (lo_open && v == lo)) {
      std::ostringstream msg;
      msg << "effect '" << name << "': '" << key << "' = " << v << " is out of range " << (lo_open ? "(" : "[") << lo
          << ", " << hi << "]";
      throw InputError(msg.str());
    }
    return v;
  };
  const double inf = std::numeric_limits<double>::infinity();
  if (name == "time_delay") {
    effects->time_delay = get("delay", 0, 1, false);
  } else if (name == "velocity_saturation") {
    if (parameters.empty()) throw InputError("effect 'velocity_saturation': needs v_max, w_max or both");
    effects->v_max = parameters.count("v_max") ? get("v_max", 0, inf, true) : 0;
    effects->w_max = parameters.count("w_max") ? get("w_max", 0, inf, true) : 0;
  } else if (name == "traction_limit") {
    effects->a_max = get("a_max", 0, inf, true);
  } else if (name == "motor_lag") {
    if (!parameters.count("time_constant") && !parameters.count("forward") && !parameters.count("sideways") &&
        !parameters.count("turn")) {
      throw InputError("effect 'motor_lag': needs time_constant or per-axis time constants");
    }
    effects->motor_lag = parameters.count("time_constant") ? get("time_constant", 0, 10, false) : 0;
    for (int a = 0; a < 3; ++a) effects->axis_lag[static_cast<std::size_t>(a)] = parameters.count(kOmniAxisNames[a]) ? get(kOmniAxisNames[a], 0, 10, false) : 0;
    effects->lag_braking = parameters.count("braking") ? get("braking", 0.05, 20, false) : 1;
    if (parameters.count("field_frame")) {
      const double f = parameters.at("field_frame");
      if (f != 0 && f != 1) throw InputError("effect 'motor_lag': 'field_frame' must be 0 (robot frame) or 1 (field frame)");
      effects->lag_field_frame = f == 1;
    } else {
      effects->lag_field_frame = false;
    }
  } else if (name == "velocity_scale") {
    if (parameters.empty()) throw InputError("effect 'velocity_scale': needs scale or per-axis scales");
    effects->velocity_scale = parameters.count("scale") ? get("scale", 0.2, 5, false) : 1;
    for (int a = 0; a < 3; ++a) effects->axis_scale[static_cast<std::size_t>(a)] = parameters.count(kOmniAxisNames[a]) ? get(kOmniAxisNames[a], 0.02, 5, false) : 1;
  } else if (name == "rotation_drift") {
    effects->rotation_drift = get("rate", -10, 10, false);
  } else if (name == "turn_coupling") {
    if (parameters.empty()) throw InputError("effect 'turn_coupling': needs forward, sideways or both");
    effects->turn_per_forward = parameters.count("forward") ? get("forward", -20, 20, false) : 0;
    effects->turn_per_sideways = parameters.count("sideways") ? get("sideways", -20, 20, false) : 0;
  } else if (name == "cross_coupling") {
    if (parameters.empty()) throw InputError("effect 'cross_coupling': needs sideways_per_forward, forward_per_sideways or both");
    effects->sideways_per_forward = parameters.count("sideways_per_forward") ? get("sideways_per_forward", -2, 2, false) : 0;
    effects->forward_per_sideways = parameters.count("forward_per_sideways") ? get("forward_per_sideways", -2, 2, false) : 0;
  }
}

std::vector<std::pair<std::string, std::map<std::string, double>>> ListOmniEffects(const OmniEffects& e) {
  std::vector<std::pair<std::string, std::map<std::string, double>>> out;
  if (e.time_delay > 0) out.push_back({"time_delay", {{"delay", e.time_delay}}});
  if (e.v_max > 0 || e.w_max > 0) {
    std::map<std::string, double> p;
    if (e.v_max > 0) p["v_max"] = e.v_max;
    if (e.w_max > 0) p["w_max"] = e.w_max;
    out.push_back({"velocity_saturation", p});
  }
  if (e.a_max > 0) out.push_back({"traction_limit", {{"a_max", e.a_max}}});
  if (e.motor_lag > 0 || e.axis_lag != std::array<double, 3>{0, 0, 0}) {
    std::map<std::string, double> p;
    if (e.motor_lag > 0) p["time_constant"] = e.motor_lag;
    for (int a = 0; a < 3; ++a)
      if (e.axis_lag[static_cast<std::size_t>(a)] > 0) p[kOmniAxisNames[a]] = e.axis_lag[static_cast<std::size_t>(a)];
    if (e.lag_braking != 1) p["braking"] = e.lag_braking;
    if (e.lag_field_frame) p["field_frame"] = 1;
    out.push_back({"motor_lag", p});
  }
  if (e.velocity_scale != 1 || e.axis_scale != std::array<double, 3>{1, 1, 1}) {
    std::map<std::string, double> p;
    if (e.velocity_scale != 1) p["scale"] = e.velocity_scale;
    for (int a = 0; a < 3; ++a)
      if (e.axis_scale[static_cast<std::size_t>(a)] != 1) p[kOmniAxisNames[a]] = e.axis_scale[static_cast<std::size_t>(a)];
    out.push_back({"velocity_scale", p});
  }
  if (e.rotation_drift != 0) out.push_back({"rotation_drift", {{"rate", e.rotation_drift}}});
  if (e.turn_per_forward != 0 || e.turn_per_sideways != 0) {
    std::map<std::string, double> p;
    if (e.turn_per_forward != 0) p["forward"] = e.turn_per_forward;
    if (e.turn_per_sideways != 0) p["sideways"] = e.turn_per_sideways;
    out.push_back({"turn_coupling", p});
  }
  if (e.sideways_per_forward != 0 || e.forward_per_sideways != 0) {
    std::map<std::string, double> p;
    if (e.sideways_per_forward != 0) p["sideways_per_forward"] = e.sideways_per_forward;
    if (e.forward_per_sideways != 0) p["forward_per_sideways"] = e.forward_per_sideways;
    out.push_back({"cross_coupling", p});
  }
  return out;
}

}  // namespace twinsim
