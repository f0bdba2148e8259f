#include "robots/omni/omni_effects.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace twinsim {

namespace {

// A plain number of OmniEffects.
#define TWINSIM_OMNI_NUMBER(member)                                  \
  [](const OmniEffects& e) { return e.member; }, [](OmniEffects* e, double v) { e->member = v; }
// One axis of a per-axis array of OmniEffects.
#define TWINSIM_OMNI_AXIS(member, axis)                              \
  [](const OmniEffects& e) { return e.member[axis]; }, [](OmniEffects* e, double v) { e->member[axis] = v; }

std::vector<OmniEffectSpec> MakeOmniEffectSpecs() {
  //  key, lower, upper, positive, off, modifier, binary, get and set; where searched, the
  //  diagnosis's search range (lower, upper, in logarithms)
  return {
      {"time_delay", "s", "", "delay",
       {{"delay", 0, 1, false, 0, false, false, TWINSIM_OMNI_NUMBER(time_delay), 0, 1, false}}},
      {"velocity_saturation", "m/s, rad/s", "v_max, w_max or both", "v_max",
       {{"v_max", 0, 100, true, 0, false, false, TWINSIM_OMNI_NUMBER(v_max), 0.02, 20, true},
        {"w_max", 0, 1000, true, 0, false, false, TWINSIM_OMNI_NUMBER(w_max), 0.05, 100, true}}},
      {"traction_limit", "m/s^2", "", "a_max",
       {{"a_max", 0, 1e4, true, 0, false, false, TWINSIM_OMNI_NUMBER(a_max), 0.02, 100, true}}},
      {"motor_lag", "s", "time_constant, per-axis time constants or series", "time_constant",
       {{"time_constant", 0, 10, false, 0, false, false, TWINSIM_OMNI_NUMBER(motor_lag), 1e-3, 5, true},
        {"forward", 0, 10, false, 0, false, false, TWINSIM_OMNI_AXIS(axis_lag, 0), 1e-3, 5, true},
        {"sideways", 0, 10, false, 0, false, false, TWINSIM_OMNI_AXIS(axis_lag, 1), 1e-3, 5, true},
        {"turn", 0, 10, false, 0, false, false, TWINSIM_OMNI_AXIS(axis_lag, 2), 1e-3, 5, true},
        {"series", 0, 10, false, 0, false, false, TWINSIM_OMNI_NUMBER(lag_series), 1e-3, 5, true},
        {"braking", 0.05, 20, false, 1, true, false, TWINSIM_OMNI_NUMBER(lag_braking)},
        {"field_frame", 0, 1, false, 0, true, true, [](const OmniEffects& e) { return e.lag_field_frame ? 1.0 : 0.0; },
         [](OmniEffects* e, double v) { e->lag_field_frame = v == 1; }}}},
      {"velocity_scale", "times as fast", "scale or per-axis scales", "scale",
       {{"scale", 0.2, 5, false, 1, false, false, TWINSIM_OMNI_NUMBER(velocity_scale), 0.2, 5, false},
        {"forward", 0.02, 5, false, 1, false, false, TWINSIM_OMNI_AXIS(axis_scale, 0)},
        {"sideways", 0.02, 5, false, 1, false, false, TWINSIM_OMNI_AXIS(axis_scale, 1)},
        {"turn", 0.02, 5, false, 1, false, false, TWINSIM_OMNI_AXIS(axis_scale, 2)}}},
      {"rotation_drift", "rad per metre", "", "rate",
       {{"rate", -10, 10, false, 0, false, false, TWINSIM_OMNI_NUMBER(rotation_drift), -10, 10, false}}},
      {"turn_coupling", "rad/s per m/s", "forward, sideways, third_sin or third_cos (any of them)", "sideways",
       {{"forward", -20, 20, false, 0, false, false, TWINSIM_OMNI_NUMBER(turn_per_forward), -20, 20, false},
        {"sideways", -20, 20, false, 0, false, false, TWINSIM_OMNI_NUMBER(turn_per_sideways), -20, 20, false},
        // A three-wheel robot's turn that varies with the direction it drives in (issue
        // 64): identify's, not searched by the diagnosis.
        {"third_sin", -20, 20, false, 0, false, false, TWINSIM_OMNI_NUMBER(turn_third_sin)},
        {"third_cos", -20, 20, false, 0, false, false, TWINSIM_OMNI_NUMBER(turn_third_cos)}}},
      {"cross_coupling", "m/s per m/s", "sideways_per_forward, forward_per_sideways or both", "sideways_per_forward",
       {{"sideways_per_forward", -2, 2, false, 0, false, false, TWINSIM_OMNI_NUMBER(sideways_per_forward), -2, 2,
         false},
        {"forward_per_sideways", -2, 2, false, 0, false, false, TWINSIM_OMNI_NUMBER(forward_per_sideways), -2, 2,
         false}}},
  };
}

#undef TWINSIM_OMNI_NUMBER
#undef TWINSIM_OMNI_AXIS

// Value `v` of field `f` of effect `name`, checked against its range.
double CheckedValue(const std::string& name, const OmniEffectField& f, double v) {
  if (f.binary) {
    if (v != 0 && v != 1) throw InputError("effect '" + name + "': '" + f.key + "' must be 0 (robot frame) or 1 (field frame)");
    return v;
  }
  if (v < f.lower || v > f.upper || (f.positive && v == f.lower)) {
    std::ostringstream msg;
    msg << "effect '" << name << "': '" << f.key << "' = " << v << " is out of range " << (f.positive ? "(" : "[") << f.lower
        << ", " << f.upper << "]";
    throw InputError(msg.str());
  }
  return v;
}

}  // namespace

bool OmniEffectSpec::On(const OmniEffects& effects) const {
  for (const OmniEffectField& f : fields) {
    if (!f.modifier && f.get(effects) != f.off) return true;
  }
  return false;
}

const OmniEffectField* OmniEffectSpec::Field(const std::string& key) const {
  for (const OmniEffectField& f : fields)
    if (key == f.key) return &f;
  return nullptr;
}

const std::vector<OmniEffectSpec>& OmniEffectSpecs() {
  static const std::vector<OmniEffectSpec> specs = MakeOmniEffectSpecs();
  return specs;
}

const OmniEffectSpec* FindOmniEffectSpec(const std::string& name) {
  for (const OmniEffectSpec& spec : OmniEffectSpecs()) {
    if (name == spec.name) return &spec;
  }
  return nullptr;
}

std::vector<std::string> OmniEffects::Active() const {
  std::vector<std::string> names;
  for (const OmniEffectSpec& spec : OmniEffectSpecs()) {
    if (spec.On(*this)) names.push_back(spec.name);
  }
  return names;
}

const std::vector<std::string>& OmniEffectNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const OmniEffectSpec& spec : OmniEffectSpecs()) n.push_back(spec.name);
    return n;
  }();
  return names;
}

std::vector<std::string> OmniEffectParameters(const std::string& name) {
  std::vector<std::string> keys;
  if (const OmniEffectSpec* spec = FindOmniEffectSpec(name)) {
    for (const OmniEffectField& f : spec->fields) keys.push_back(f.key);
  }
  return keys;
}

void SetOmniEffect(const std::string& name, const std::map<std::string, double>& parameters, OmniEffects* effects) {
  const OmniEffectSpec* spec = FindOmniEffectSpec(name);
  if (!spec) {
    std::string known;
    for (const auto& n : OmniEffectNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown omni effect '" + name + "' (known: " + known + ")");
  }
  std::string known;
  for (const OmniEffectField& f : spec->fields) known += (known.empty() ? "" : ", ") + std::string(f.key);
  for (const auto& [key, value] : parameters) {
    if (!spec->Field(key)) {
      throw InputError("effect '" + name + "': unknown parameter '" + key + "' (known: " + known + ")");
    }
    if (!std::isfinite(value)) throw InputError("effect '" + name + "': '" + key + "' is not a finite number");
  }
  int switching = 0, given = 0;
  for (const OmniEffectField& f : spec->fields) {
    if (f.modifier) continue;
    ++switching;
    given += static_cast<int>(parameters.count(f.key));
  }
  if (given == 0) {
    if (switching > 1) throw InputError("effect '" + name + "': needs " + spec->needs);
    throw InputError("effect '" + name + "': missing parameter '" + spec->missing_key + "'");
  }
  for (const OmniEffectField& f : spec->fields) {
    const auto it = parameters.find(f.key);
    f.set(effects, it == parameters.end() ? f.off : CheckedValue(name, f, it->second));
  }
}

std::vector<std::pair<std::string, std::map<std::string, double>>> ListOmniEffects(const OmniEffects& e) {
  std::vector<std::pair<std::string, std::map<std::string, double>>> out;
  for (const OmniEffectSpec& spec : OmniEffectSpecs()) {
    if (!spec.On(e)) continue;
    std::map<std::string, double> p;
    for (const OmniEffectField& f : spec.fields) {
      if (f.get(e) != f.off) p[f.key] = f.get(e);
    }
    out.push_back({spec.name, p});
  }
  return out;
}

}  // namespace twinsim
