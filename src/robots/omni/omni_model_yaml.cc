// Reading OmniModel from YAML; the schema is documented in docs/models.md.
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/engine_names.h"
#include "core/math_constants.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "robots/omni/omni_effects.h"
#include "robots/omni/omni_model.h"

namespace twinsim {
namespace {

void ReadPid(YamlMap& parent, const std::string& key, PidGains* g) {
  if (!parent.Has(key)) return;
  YamlMap m(parent.Child(key), parent.path(), "controller." + key, parent.errors());
  m.Get("kp", &g->kp, NonNegative(1e6));
  m.Get("ki", &g->ki, NonNegative(1e6));
  m.Get("kd", &g->kd, NonNegative(1e6));
  m.Get("integral_limit", &g->integral_limit, NonNegative(1e6));
  m.Get("output_limit", &g->output_limit, NonNegative(1e6));
  m.Get("slew_rate", &g->slew_rate, NonNegative(1e6));
  m.Finish();
}

// observer.seen_inputs: {scale, covering, points: [[u1..u2n], ...]} (omni_seen_inputs.h);
// the points' length is checked against the wheels by Validate.
void ReadSeenInputs(YamlMap& observer, OmniSeenInputs* out) {
  YamlMap m(observer.Child("seen_inputs"), observer.path(), "observer.seen_inputs", observer.errors());
  if (!m.valid()) return;
  m.Require("scale", &out->scale, Positive(1e6));
  m.Get("covering", &out->covering, NonNegative(1e6));
  const YAML::Node points = m.Child("points");
  if (!points.IsSequence() || points.size() == 0 || points.size() > static_cast<std::size_t>(kMaxSeenInputs)) {
    m.Error("points", "must be a list of 1 to " + std::to_string(kMaxSeenInputs) +
                          " inputs, each a list of wheel speeds (rad/s: the command's, then the body's)");
  } else {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::string label = "observer.seen_inputs.points[" + std::to_string(i) + "]";
      if (!points[i].IsSequence()) {
        m.Error("points", label + " must be a list of wheel speeds");
        break;
      }
      Eigen::VectorXd u(static_cast<long>(points[i].size()));
      bool ok = true;
      for (std::size_t j = 0; j < points[i].size() && ok; ++j) {
        const std::optional<double> v = ReadNumber(points[i][j], observer.path(), label, observer.errors());
        ok = v.has_value();
        if (ok) u[static_cast<long>(j)] = *v;
      }
      if (!ok) break;
      out->points.push_back(u);
    }
  }
  m.Finish();
}

OmniModel ReadOmniModel(const YAML::Node& file_root, const std::string& path, int depth);

YAML::Node Resolve(const YAML::Node& root, const std::string& path, int depth) {
  return ResolveExtends(root, path, depth, [](const YAML::Node& base, const std::string& base_path, int d) {
    ReadOmniModel(base, base_path, d);
  });
}

OmniModel ReadOmniModel(const YAML::Node& file_root, const std::string& path, int depth) {
  ErrorList errors;
  OmniModel model;
  model.source_path = path;
  const YAML::Node root = Resolve(file_root, path, depth);
  YamlMap top(root, path, "", &errors);
  std::string kind = "omni";
  top.Get("robot", &kind, {"omni"});
  top.Has("extends");  // resolved above
  top.Require("name", &model.name);
  top.Get("fitted_on", &model.fitted_on, KnownEngines());

  if (top.Has("chassis")) {
    YamlMap c(top.Child("chassis"), path, "chassis", &errors);
    c.Get("mass", &model.chassis_mass, Positive(1000));
    c.Get("radius", &model.chassis_radius, InRange(0.01, 10));
    c.Get("height", &model.chassis_height, Positive(10));
    c.Get("inertia_z", &model.chassis_inertia_z, NonNegative(1e4));
    c.Get("com_height", &model.com_height, Positive(10));
    std::vector<double> com;
    if (c.Get("com", &com, 2, InRange(-10, 10))) model.chassis_com = Eigen::Vector2d(com[0], com[1]);
    c.Get("ground_clearance", &model.ground_clearance, NonNegative(1));
    if (c.Get("front_distance", &model.front_distance, NonNegative(10)) &&
        ((model.front_distance > 0 && model.front_distance < 0.5 * model.chassis_radius) ||
         model.front_distance >= model.chassis_radius)) {
      c.Error("front_distance", "must lie between half the radius and the radius (" +
                                    std::to_string(0.5 * model.chassis_radius) + " .. " +
                                    std::to_string(model.chassis_radius) + " m), or be 0 for the default");
    }
    c.Finish();
  } else {
    top.Missing("chassis");
  }

  if (top.Has("wheels")) {
    YamlMap w(top.Child("wheels"), path, "wheels", &errors);
    std::vector<double> angles_deg;
    if (w.Require("angles_deg", &angles_deg, -1, InRange(-360, 360))) {
      model.wheel_angles.clear();
      for (double a : angles_deg) model.wheel_angles.push_back(a * kPi / 180.0);
      if (angles_deg.size() < 3 || angles_deg.size() > 8)
        w.Error("angles_deg", "an omni robot has 3 to 8 wheels, got " + std::to_string(angles_deg.size()));
    }
    w.Get("distance", &model.wheel_distance, InRange(0.001, 10));
    w.Get("radius", &model.wheel_radius, Positive(1));
    w.Get("width", &model.wheel_width, Positive(1));
    w.Get("mass", &model.wheel_mass, Positive(100));
    w.Get("friction", &model.wheel_friction, Positive(100));
    w.Get("roller_friction", &model.roller_friction, NonNegative(100));
    w.Get("bearing_damping", &model.bearing_damping, NonNegative(1e3));
    w.Finish();
  } else {
    top.Missing("wheels");
  }

  if (top.Has("motor")) {
    YamlMap m(top.Child("motor"), path, "motor", &errors);
    m.Get("stall_torque", &model.motor_stall_torque, Positive(1e4));
    m.Get("no_load_speed", &model.motor_no_load_speed, Positive(1e5));
    m.Get("encoder_counts_per_rev", &model.encoder_counts_per_rev, NonNegative(1e9));
    m.Get("strength", &model.motor_strength, -1, InRange(0.01, 2));
    m.Finish();
  }

  if (top.Has("controller")) {
    YamlMap c(top.Child("controller"), path, "controller", &errors);
    c.Get("rate_hz", &model.controller.rate_hz, InRange(1, 100000));
    ReadPid(c, "forward", &model.controller.forward);
    ReadPid(c, "sideways", &model.controller.sideways);
    ReadPid(c, "rotation", &model.controller.rotation);
    c.Finish();
  }

  if (top.Has("kicker")) {
    YamlMap k(top.Child("kicker"), path, "kicker", &errors);
    k.Get("max_speed", &model.kicker_max_speed, InRange(0.1, 20));
    k.Finish();
  }
  if (top.Has("dribbler")) {
    YamlMap d(top.Child("dribbler"), path, "dribbler", &errors);
    d.Get("max_force", &model.dribbler_max_force, InRange(0, 100));
    d.Get("full_speed", &model.dribbler_full_speed, InRange(0, 1e5));
    d.Finish();
  }

  if (top.Has("delay")) {
    YamlMap d(top.Child("delay"), path, "delay", &errors);
    d.Get("command_frames", &model.command_delay_frames, InRange(0, 100));
    d.Get("vision_frames", &model.vision_delay_frames, InRange(0, 100));
    d.Finish();
  }

  if (top.Has("effects")) {
    // Every effect's keys and ranges from the vocabulary's table (omni_effects.h); a key
    // the file leaves out stays off (`extends:` is merged into the YAML before this).
    YamlMap e(top.Child("effects"), path, "effects", &errors);
    for (const OmniEffectSpec& spec : OmniEffectSpecs()) {
      if (!e.Has(spec.name)) continue;
      YamlMap m(e.Child(spec.name), path, std::string("effects.") + spec.name, &errors);
      auto read = [&](const OmniEffectField& f) {
        if (f.binary) {
          int v = static_cast<int>(f.get(model.effects));
          if (m.Get(f.key, &v, InRange(0, 1))) f.set(&model.effects, v);
        } else {
          double v = f.get(model.effects);
          if (m.Get(f.key, &v, f.positive ? Positive(f.upper) : InRange(f.lower, f.upper))) f.set(&model.effects, v);
        }
      };
      bool given = false;  // one of the keys that switch it on
      for (const OmniEffectField& f : spec.fields) {
        if (f.modifier) continue;
        given = given || m.Has(f.key);
        read(f);
      }
      if (!given) m.Missing(spec.missing_key);
      for (const OmniEffectField& f : spec.fields) {
        if (f.modifier) read(f);
      }
      m.Finish();
    }
    e.Finish();
  }

  if (top.Has("vision")) {
    YamlMap v(top.Child("vision"), path, "vision", &errors);
    v.Get("noise_xy", &model.vision_noise_xy, NonNegative(10));
    v.Get("noise_theta", &model.vision_noise_theta, NonNegative(10));
    v.Get("drop_probability", &model.vision_drop_probability, InRange(0, 0.9));
    v.Get("repeat_probability", &model.vision_repeat_probability, InRange(0, 0.9));
    v.Get("time_jitter", &model.vision_time_jitter, InRange(0, 0.005));
    v.Finish();
  }

  if (top.Has("driving_noise")) {
    YamlMap d(top.Child("driving_noise"), path, "driving_noise", &errors);
    for (int a = 0; a < 3; ++a) d.Get(kOmniAxisNames[a], &model.driving_noise.sd[static_cast<std::size_t>(a)], NonNegative(100));
    d.Get("correlation_time", &model.driving_noise.correlation_time, InRange(1e-3, 100));
    d.Get("per_speed", &model.driving_noise.per_speed, NonNegative(100));
    d.Get("per_acceleration", &model.driving_noise.per_acceleration, NonNegative(100));
    d.Get("per_turn_rate", &model.driving_noise.per_turn_rate, NonNegative(100));
    d.Get("simulated", &model.driving_noise.simulated);
    if (d.Has("drift")) {
      YamlMap b(d.Child("drift"), path, "driving_noise.drift", &errors);
      for (int a = 0; a < 3; ++a)
        b.Get(kOmniAxisNames[a], &model.driving_noise.drift.sd[static_cast<std::size_t>(a)], NonNegative(100));
      b.Get("correlation_time", &model.driving_noise.drift.correlation_time, InRange(0.1, 1000));
      b.Finish();
    }
    d.Finish();
  }
  if (top.Has("observer")) {
    YamlMap o(top.Child("observer"), path, "observer", &errors);
    if (o.Has("process_noise")) {
      YamlMap q(o.Child("process_noise"), path, "observer.process_noise", &errors);
      for (int a = 0; a < 3; ++a)
        q.Get(kOmniAxisNames[a], &model.observer.process_noise[static_cast<std::size_t>(a)], InRange(1e-6, 1e3));
      q.Finish();
    }
    if (o.Has("measurement_noise")) {
      YamlMap r(o.Child("measurement_noise"), path, "observer.measurement_noise", &errors);
      r.Get("xy", &model.observer.measurement_noise_xy, NonNegative(10));
      r.Get("theta", &model.observer.measurement_noise_theta, NonNegative(10));
      r.Finish();
    }
    if (o.Has("interval_scale")) ReadIntervalScales(o, "interval_scale", true, &model.observer.interval_scale);
    if (o.Has("seen_inputs")) ReadSeenInputs(o, &model.observer.seen_inputs);
    o.Finish();
  }
  top.Finish();
  errors.ThrowIfAny();

  model.Finalize();
  const std::string problems = model.Validate();
  if (!problems.empty()) {
    std::string all;
    std::size_t start = 0;
    while (start <= problems.size()) {
      std::size_t end = problems.find('\n', start);
      if (end == std::string::npos) end = problems.size();
      errors.Add(SourceLocation{path}, problems.substr(start, end - start));
      start = end + 1;
    }
    errors.ThrowIfAny();
  }
  return model;
}

}  // namespace

void ReadIntervalScales(YamlMap& parent, const std::string& key, bool growth,
                        std::vector<OmniObserverModel::IntervalScale>* out) {
  const YAML::Node list = parent.Child(key);
  if (!list.IsSequence() || list.size() == 0) {
    parent.Error(key, "must be a list of {frames: K, position: s, heading: s}, horizons increasing");
    return;
  }
  constexpr double kMost = OmniObserverModel::kMaxIntervalScale;
  const std::string label = parent.context().empty() ? key : parent.context() + "." + key;
  out->clear();
  for (std::size_t i = 0; i < list.size(); ++i) {
    YamlMap m(list[i], parent.path(), label + "[" + std::to_string(i) + "]", parent.errors());
    if (!m.valid()) continue;
    OmniObserverModel::IntervalScale h;
    m.Require("frames", &h.frames, InRange(1, 1e6));
    m.Require("position", &h.position, InRange(1 / kMost, kMost));
    m.Require("heading", &h.heading, InRange(1 / kMost, kMost));
    if (growth) {
      m.Get("position_growth", &h.position_growth, NonNegative(OmniObserverModel::kMaxIntervalGrowth));
      m.Get("heading_growth", &h.heading_growth, NonNegative(OmniObserverModel::kMaxIntervalGrowth));
    }
    if (!out->empty() && h.frames <= out->back().frames)
      m.Error("frames", "the horizons must increase from one entry to the next");
    m.Finish();
    out->push_back(h);
  }
}

OmniModel LoadOmniModel(const std::string& path) { return ReadOmniModel(LoadYamlFile(path), path, 0); }

OmniModel LoadOmniModel(const std::string& path, const YamlOverrides& overrides) {
  if (overrides.empty()) return LoadOmniModel(path);
  return ReadOmniModel(ApplyYamlOverrides(LoadYamlFile(path), overrides, path), path, 0);
}

OmniModel LoadOmniModelFromString(const std::string& yaml, const std::string& name) {
  YAML::Node root = LoadYamlString(yaml, name);
  if (!root.IsMap()) throw InputError(SourceLocation{name, 1}, "expected a YAML mapping at the top level");
  return ReadOmniModel(root, name, 0);
}

}  // namespace twinsim
