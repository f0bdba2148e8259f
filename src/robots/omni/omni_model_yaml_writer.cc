#include "robots/omni/omni_model_yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <sstream>

#include "core/math_constants.h"
#include "io/atomic_file.h"
#include "io/yaml_number.h"
#include "robots/omni/omni_effects.h"
#include "robots/omni/omni_model_fields.h"

namespace twinsim {
namespace {

// An angle in degrees that the reader (deg * kPi / 180.0) turns back into `rad`: the
// plain inverse can be an ulp off, so the doubles next to it are tried too, and the
// shortest exact one wins (57, not 57.000000000000007).
std::string Degrees(double rad) {
  double d = rad * 180.0 / kPi;
  for (int i = 0; i < 8; ++i) d = std::nextafter(d, -INFINITY);
  std::string best;
  double best_error = INFINITY;
  for (int i = 0; i <= 16; ++i, d = std::nextafter(d, INFINITY)) {
    const double error = std::abs(d * kPi / 180.0 - rad);
    const std::string text = YamlNumber(d);
    if (error < best_error || (error == best_error && text.size() < best.size())) {
      best = text;
      best_error = error;
    }
  }
  return best;
}

// A YAML scalar for a name, quoted only when it must be.
std::string Text(const std::string& s) {
  YAML::Emitter out;
  out << s;
  return out.c_str();
}

// A field's value as the file writes it.
std::string Value(const OmniModelField& f, const OmniModel& model) {
  const double v = f.get(model);
  return f.integer ? std::to_string(static_cast<int>(v)) : YamlNumber(v);
}

// The numbers of `section` (omni_model_fields.h) as a flow map, "{key: value, ...}", in
// the table's order; a key that is not one number gets the text `custom` gives it ("" for
// none).
std::string FlowMap(const std::string& section, const OmniModel& model,
                    const std::function<std::string(const OmniModelField&)>& custom = {}) {
  std::string out;
  for (const OmniModelField* f : OmniModelFieldsOf(section)) {
    std::string item;
    if (f->custom) {
      if (custom) item = custom(*f);
    } else if (!f->omitted_at_zero || f->get(model) != 0) {
      item = f->key + ": " + Value(*f, model);
    }
    if (!item.empty()) out += (out.empty() ? "" : ", ") + item;
  }
  return "{" + out + "}";
}

}  // namespace

std::string FormatOmniModelYaml(const OmniModel& model, const std::string& comment) {
  std::ostringstream s;
  // "  key: value", the unit comment aligned as in the shipped models.
  auto line = [&s](const std::string& key, const std::string& value, const std::string& unit = "",
                   std::size_t column = 26) {
    std::string text = key + ": " + value;
    if (!unit.empty()) text += std::string(text.size() < column ? column - text.size() : 1, ' ') + "# " + unit;
    s << text << "\n";
  };
  if (!comment.empty()) {
    std::istringstream lines(comment);
    std::string l;
    while (std::getline(lines, l)) s << "# " << l << "\n";
  }
  // "  key: value  # unit" for the numbers of `section`, in the table's order; a key that
  // is not one number is written by `custom` at its place.
  auto lines = [&](const std::string& section, const std::function<void(const OmniModelField&)>& custom = {}) {
    for (const OmniModelField* f : OmniModelFieldsOf(section)) {
      if (f->custom) {
        if (custom) custom(*f);
      } else if (!f->omitted_at_zero || f->get(model) != 0) {
        line("  " + f->key, Value(*f, model), f->unit);
      }
    }
  };
  line("robot", "omni");
  line("name", Text(model.name));
  if (!model.fitted_on.empty()) line("fitted_on", model.fitted_on, "the engine the response was fitted on");
  s << "chassis:\n";
  lines("chassis", [&](const OmniModelField& f) {  // com
    if (model.chassis_com.isZero()) return;
    line("  " + f.key, "[" + YamlNumber(model.chassis_com.x()) + ", " + YamlNumber(model.chassis_com.y()) + "]", f.unit);
  });
  s << "wheels:\n";
  lines("wheels", [&](const OmniModelField& f) {  // angles_deg
    std::string angles;
    for (double a : model.wheel_angles) angles += (angles.empty() ? "" : ", ") + Degrees(a);
    line("  " + f.key, "[" + angles + "]", f.unit);
  });
  s << "motor:\n";
  lines("motor", [&](const OmniModelField& f) {  // strength
    if (model.motor_strength.empty()) return;
    std::string strength;
    for (double v : model.motor_strength) strength += (strength.empty() ? "" : ", ") + YamlNumber(v);
    line("  " + f.key, "[" + strength + "]", f.unit);
  });
  const OmniModel defaults;
  if (model.kicker_max_speed != defaults.kicker_max_speed) {
    s << "kicker:\n";
    lines("kicker");
  }
  if (model.dribbler_max_force != defaults.dribbler_max_force ||
      model.dribbler_full_speed != defaults.dribbler_full_speed) {
    s << "dribbler:\n";
    lines("dribbler");
  }
  s << "controller:\n";
  lines("controller");
  s << "  # kp N per m/s, ki N per m, kd N per m/s^2, limits N, slew_rate m/s^2\n"
       "  # (rotation: N·m and rad); a limit of 0 is no limit\n";
  for (const char* axis : {"forward", "sideways", "rotation"})
    line(std::string("  ") + axis, FlowMap(std::string("controller.") + axis, model));
  s << "delay:\n";
  lines("delay");
  s << "vision:\n";
  lines("vision");
  const OmniDrivingNoise& dn = model.driving_noise;
  if (dn.sd != defaults.driving_noise.sd || dn.correlation_time != defaults.driving_noise.correlation_time ||
      dn.per_speed != 0 || dn.per_acceleration != 0 || dn.per_turn_rate != 0 || dn.simulated || dn.drift.any()) {
    line("driving_noise", FlowMap("driving_noise", model, [&](const OmniModelField& f) -> std::string {
           if (f.key == "simulated") return dn.simulated ? f.key + ": true" : "";
           return dn.drift.any() ? f.key + ": " + FlowMap(f.path(), model) : "";  // drift
         }),
         "m/s, rad/s, s: slip the wheels do not see", 46);
  }
  const OmniObserverModel& o = model.observer;
  if (o.process_noise != defaults.observer.process_noise || o.measurement_noise_xy > 0 ||
      o.measurement_noise_theta > 0 || !o.interval_scale.empty() || !o.seen_inputs.empty() ||
      !o.parameter_covariance.empty()) {
    s << "observer:\n";
    line("  process_noise", FlowMap("observer.process_noise", model), "m/s and rad/s per sqrt(s): the model's own errors", 46);
    if (o.measurement_noise_xy > 0 || o.measurement_noise_theta > 0)
      line("  measurement_noise", FlowMap("observer.measurement_noise", model), "m, rad; 0 = the vision block's", 46);
    if (!o.interval_scale.empty()) {
      s << "  interval_scale:  # the predicted covariance's scale k frames ahead (identify's safeguard)\n";
      for (const OmniObserverModel::IntervalScale& h : o.interval_scale) {
        s << "    - {frames: " << h.frames << ", position: " << YamlNumber(h.position)
          << ", heading: " << YamlNumber(h.heading);
        if (h.position_growth > 0) s << ", position_growth: " << YamlNumber(h.position_growth);
        if (h.heading_growth > 0) s << ", heading_growth: " << YamlNumber(h.heading_growth);
        s << "}\n";
      }
    }
    if (!o.seen_inputs.empty()) {
      s << "  seen_inputs:  # the fit's inputs, wheel speeds (rad/s) of the command, then the body's; distances over scale\n";
      s << "    scale: " << YamlNumber(o.seen_inputs.scale) << "\n";
      s << "    covering: " << YamlNumber(o.seen_inputs.covering) << "\n";
      s << "    points:\n";
      for (const Eigen::VectorXd& u : o.seen_inputs.points) {
        s << "      - [";
        for (long j = 0; j < u.size(); ++j) s << (j ? ", " : "") << YamlNumber(u[j]);
        s << "]\n";
      }
    }
    if (!o.parameter_covariance.empty()) {
      const OmniObserverModel::ParameterCovariance& pc = o.parameter_covariance;
      s << "  parameter_covariance:  # identify's estimate of the response's parameters: their covariance (its names and units)\n";
      s << "    parameters: [";
      for (std::size_t i = 0; i < pc.parameters.size(); ++i) s << (i ? ", " : "") << pc.parameters[i];
      s << "]\n    matrix:\n";
      for (long i = 0; i < pc.matrix.rows(); ++i) {
        s << "      - [";
        for (long j = 0; j < pc.matrix.cols(); ++j) s << (j ? ", " : "") << YamlNumber(pc.matrix(i, j));
        s << "]\n";
      }
    }
  }

  // Only what is on, with the parameters ListOmniEffects gives (the reader's keys) and
  // the vocabulary's units.
  const auto effects = ListOmniEffects(model.effects);
  if (!effects.empty()) s << "effects:\n";
  for (const auto& [name, parameters] : effects) {
    std::string values;
    for (const auto& [key, value] : parameters) values += (values.empty() ? "" : ", ") + key + ": " + YamlNumber(value);
    line("  " + name, "{" + values + "}", FindOmniEffectSpec(name)->unit, 46);
  }
  return s.str();
}

void WriteOmniModelYaml(const std::string& path, const OmniModel& model, const std::string& comment) {
  WriteFileAtomically(path, FormatOmniModelYaml(model, comment));
}

}  // namespace twinsim
