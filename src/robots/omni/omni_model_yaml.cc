// Reading OmniModel from YAML; the schema is documented in docs/models.md.
#include <cmath>
#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/engine_names.h"
#include "core/math_constants.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "robots/omni/omni_effects.h"
#include "robots/omni/omni_model.h"
#include "robots/omni/omni_model_fields.h"

namespace twinsim {
namespace {

// Reads the numbers of `section` (omni_model_fields.h) from `m`, in the table's order; a
// key that is not one number is read by `custom` at its place.
void ReadFields(YamlMap& m, const std::string& section, OmniModel* model,
                const std::function<void(const OmniModelField&)>& custom = {}) {
  for (const OmniModelField* f : OmniModelFieldsOf(section)) {
    if (f->custom) {
      if (custom) custom(*f);
    } else if (f->integer) {
      int v = static_cast<int>(f->get(*model));
      if (m.Get(f->key, &v, f->check)) f->set(model, v);
    } else {
      double v = f->get(*model);
      if (m.Get(f->key, &v, f->check)) f->set(model, v);
    }
  }
}

// A section of its own under `parent` (controller.forward, observer.process_noise):
// its numbers, and no other key.
void ReadSubsection(YamlMap& parent, const std::string& key, const std::string& section, OmniModel* model) {
  if (!parent.Has(key)) return;
  YamlMap m(parent.Child(key), parent.path(), section, parent.errors());
  ReadFields(m, section, model);
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

// observer.parameter_covariance: {parameters: [names], matrix: [[...], ...]}; the names
// are identify's, which the replay checks where it uses them; the shape by Validate.
void ReadParameterCovariance(YamlMap& observer, OmniObserverModel::ParameterCovariance* out) {
  YamlMap m(observer.Child("parameter_covariance"), observer.path(), "observer.parameter_covariance", observer.errors());
  if (!m.valid()) return;
  constexpr int kMost = OmniObserverModel::kMaxCovarianceParameters;
  const YAML::Node names = m.Child("parameters");
  if (!names.IsSequence() || names.size() == 0 || names.size() > static_cast<std::size_t>(kMost)) {
    m.Error("parameters", "must be a list of 1 to " + std::to_string(kMost) + " parameter names (identify's)");
  } else {
    for (const YAML::Node& n : names) {
      if (!n.IsScalar() || n.Scalar().empty()) {
        m.Error("parameters", "must be a list of parameter names (identify's, e.g. delay, forward.gain)");
        out->parameters.clear();
        break;
      }
      out->parameters.push_back(n.Scalar());
    }
  }
  const YAML::Node rows = m.Child("matrix");
  const std::size_t k = out->parameters.size();
  if (!rows.IsSequence() || (k > 0 && rows.size() != k)) {
    m.Error("matrix", "must be a list of " + std::to_string(k) + " rows, one per parameter");
  } else if (k > 0) {
    out->matrix.resize(static_cast<long>(k), static_cast<long>(k));
    for (std::size_t i = 0; i < k; ++i) {
      const std::string label = "observer.parameter_covariance.matrix[" + std::to_string(i) + "]";
      if (!rows[i].IsSequence() || rows[i].size() != k) {
        m.Error("matrix", label + " must be a list of " + std::to_string(k) + " numbers");
        out->matrix.resize(0, 0);
        break;
      }
      for (std::size_t j = 0; j < k; ++j) {
        const std::optional<double> v = ReadNumber(rows[i][j], observer.path(), label, observer.errors());
        out->matrix(static_cast<long>(i), static_cast<long>(j)) = v.value_or(std::nan(""));
      }
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
  RequireModelKind(root, path, RobotKind::kOmni);
  YamlMap top(root, path, "", &errors);
  std::string kind = "omni";
  top.Get("robot", &kind, {"omni"});
  top.Has("extends");  // resolved above
  top.Require("name", &model.name);
  top.Get("fitted_on", &model.fitted_on, KnownEngines());

  if (top.Has("chassis")) {
    YamlMap c(top.Child("chassis"), path, "chassis", &errors);
    ReadFields(c, "chassis", &model, [&](const OmniModelField& f) {  // com
      std::vector<double> com;
      if (c.Get(f.key, &com, 2, InRange(-10, 10))) model.chassis_com = Eigen::Vector2d(com[0], com[1]);
    });
    // front_distance, the section's last key: 0 where not given (or not valid).
    if ((model.front_distance > 0 && model.front_distance < 0.5 * model.chassis_radius) ||
        model.front_distance >= model.chassis_radius) {
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
    ReadFields(w, "wheels", &model, [&](const OmniModelField& f) {  // angles_deg
      std::vector<double> angles_deg;
      if (w.Require(f.key, &angles_deg, -1, InRange(-360, 360))) {
        model.wheel_angles.clear();
        for (double a : angles_deg) model.wheel_angles.push_back(a * kPi / 180.0);
        if (angles_deg.size() < 3 || angles_deg.size() > 8)
          w.Error(f.key, "an omni robot has 3 to 8 wheels, got " + std::to_string(angles_deg.size()));
        // Two wheels on one spot, said here with the list's line (OmniModel::Validate
        // says it too, of a model built in code), the first pair only.
        bool said = false;
        const std::vector<double>& angles = model.wheel_angles;
        for (std::size_t i = 0; i < angles.size() && !said; ++i) {
          for (std::size_t j = i + 1; j < angles.size() && !said; ++j) {
            if (SameWheelAngle(angles[i], angles[j])) {
              w.Error(f.key, "wheels " + std::to_string(i + 1) + " and " + std::to_string(j + 1) +
                                 " are at the same angle");
              said = true;
            }
          }
        }
      }
    });
    w.Finish();
  } else {
    top.Missing("wheels");
  }

  if (top.Has("motor")) {
    YamlMap m(top.Child("motor"), path, "motor", &errors);
    ReadFields(m, "motor", &model, [&](const OmniModelField& f) {  // strength
      m.Get(f.key, &model.motor_strength, -1, InRange(0.01, 2));
    });
    m.Finish();
  }

  if (top.Has("controller")) {
    YamlMap c(top.Child("controller"), path, "controller", &errors);
    ReadFields(c, "controller", &model);
    for (const char* axis : {"forward", "sideways", "rotation"})
      ReadSubsection(c, axis, std::string("controller.") + axis, &model);
    c.Finish();
  }
  for (const char* section : {"kicker", "dribbler", "delay"}) ReadSubsection(top, section, section, &model);

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

  ReadSubsection(top, "vision", "vision", &model);

  if (top.Has("driving_noise")) {
    YamlMap d(top.Child("driving_noise"), path, "driving_noise", &errors);
    ReadFields(d, "driving_noise", &model, [&](const OmniModelField& f) {
      if (f.key == "simulated") d.Get(f.key, &model.driving_noise.simulated);
      if (f.key == "drift") ReadSubsection(d, f.key, f.path(), &model);
    });
    d.Finish();
  }
  if (top.Has("observer")) {
    YamlMap o(top.Child("observer"), path, "observer", &errors);
    ReadSubsection(o, "process_noise", "observer.process_noise", &model);
    ReadSubsection(o, "measurement_noise", "observer.measurement_noise", &model);
    if (o.Has("interval_scale")) ReadIntervalScales(o, "interval_scale", true, &model.observer.interval_scale);
    if (o.Has("seen_inputs")) ReadSeenInputs(o, &model.observer.seen_inputs);
    if (o.Has("parameter_covariance")) ReadParameterCovariance(o, &model.observer.parameter_covariance);
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
