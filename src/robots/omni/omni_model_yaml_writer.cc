#include "robots/omni/omni_model_yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/math_constants.h"
#include "io/atomic_file.h"
#include "io/yaml_number.h"
#include "robots/omni/omni_effects.h"

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

// "forward: a, sideways: b, turn: c", the per-axis keys of a flow map.
std::string AxisValues(const std::array<double, 3>& v) {
  std::string out;
  for (int a = 0; a < 3; ++a)
    out += std::string(a ? ", " : "") + kOmniAxisNames[a] + ": " + YamlNumber(v[static_cast<std::size_t>(a)]);
  return out;
}

std::string Pid(const PidGains& g) {
  return "{kp: " + YamlNumber(g.kp) + ", ki: " + YamlNumber(g.ki) + ", kd: " + YamlNumber(g.kd) +
         ", integral_limit: " + YamlNumber(g.integral_limit) + ", output_limit: " + YamlNumber(g.output_limit) +
         ", slew_rate: " + YamlNumber(g.slew_rate) + "}";
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
  line("robot", "omni");
  line("name", Text(model.name));
  if (!model.fitted_on.empty()) line("fitted_on", model.fitted_on, "the engine the response was fitted on");
  s << "chassis:\n";
  line("  mass", YamlNumber(model.chassis_mass), "kg, without wheels");
  line("  radius", YamlNumber(model.chassis_radius), "m");
  line("  height", YamlNumber(model.chassis_height), "m");
  line("  inertia_z", YamlNumber(model.chassis_inertia_z), "kg m^2; 0 = solid cylinder");
  line("  com_height", YamlNumber(model.com_height), "m above the floor");
  if (!model.chassis_com.isZero()) {
    line("  com", "[" + YamlNumber(model.chassis_com.x()) + ", " + YamlNumber(model.chassis_com.y()) + "]",
         "m, the chassis' centre of mass from the centre, robot frame");
  }
  line("  ground_clearance", YamlNumber(model.ground_clearance), "m");
  if (model.front_distance > 0) line("  front_distance", YamlNumber(model.front_distance), "m, centre to the flat front");
  s << "wheels:\n";
  std::string angles;
  for (double a : model.wheel_angles) angles += (angles.empty() ? "" : ", ") + Degrees(a);
  line("  angles_deg", "[" + angles + "]", "deg, from the robot's x axis");
  line("  distance", YamlNumber(model.wheel_distance), "m, centre to wheel contact");
  line("  radius", YamlNumber(model.wheel_radius), "m");
  line("  width", YamlNumber(model.wheel_width), "m");
  line("  mass", YamlNumber(model.wheel_mass), "kg each");
  line("  friction", YamlNumber(model.wheel_friction), "along the rolling direction");
  line("  roller_friction", YamlNumber(model.roller_friction), "across the wheel");
  line("  bearing_damping", YamlNumber(model.bearing_damping), "N·m per rad/s");
  s << "motor:\n";
  line("  stall_torque", YamlNumber(model.motor_stall_torque), "N·m at the wheel");
  line("  no_load_speed", YamlNumber(model.motor_no_load_speed), "rad/s at the wheel");
  line("  encoder_counts_per_rev", YamlNumber(model.encoder_counts_per_rev), "counts; 0 = ideal encoder");
  if (!model.motor_strength.empty()) {
    std::string strength;
    for (double v : model.motor_strength) strength += (strength.empty() ? "" : ", ") + YamlNumber(v);
    line("  strength", "[" + strength + "]", "share of the stall torque, per wheel");
  }
  const OmniModel defaults;
  if (model.kicker_max_speed != defaults.kicker_max_speed) {
    s << "kicker:\n";
    line("  max_speed", YamlNumber(model.kicker_max_speed), "m/s");
  }
  if (model.dribbler_max_force != defaults.dribbler_max_force ||
      model.dribbler_full_speed != defaults.dribbler_full_speed) {
    s << "dribbler:\n";
    line("  max_force", YamlNumber(model.dribbler_max_force), "N");
    line("  full_speed", YamlNumber(model.dribbler_full_speed), "rpm");
  }
  s << "controller:\n";
  line("  rate_hz", YamlNumber(model.controller.rate_hz), "Hz");
  s << "  # kp N per m/s, ki N per m, kd N per m/s^2, limits N, slew_rate m/s^2\n"
       "  # (rotation: N·m and rad); a limit of 0 is no limit\n";
  line("  forward", Pid(model.controller.forward));
  line("  sideways", Pid(model.controller.sideways));
  line("  rotation", Pid(model.controller.rotation));
  s << "delay:\n";
  line("  command_frames", std::to_string(model.command_delay_frames), "camera frames");
  line("  vision_frames", std::to_string(model.vision_delay_frames), "camera frames");
  s << "vision:\n";
  line("  noise_xy", YamlNumber(model.vision_noise_xy), "m");
  line("  noise_theta", YamlNumber(model.vision_noise_theta), "rad");
  line("  drop_probability", YamlNumber(model.vision_drop_probability));
  if (model.vision_repeat_probability > 0) line("  repeat_probability", YamlNumber(model.vision_repeat_probability));
  if (model.vision_time_jitter > 0) line("  time_jitter", YamlNumber(model.vision_time_jitter), "s");
  const OmniDrivingNoise& dn = model.driving_noise;
  if (dn.sd != defaults.driving_noise.sd || dn.correlation_time != defaults.driving_noise.correlation_time ||
      dn.per_speed != 0 || dn.per_acceleration != 0 || dn.per_turn_rate != 0 || dn.simulated || dn.drift.any()) {
    line("driving_noise",
         "{" + AxisValues(dn.sd) + ", correlation_time: " + YamlNumber(dn.correlation_time) +
             (dn.per_speed != 0 ? ", per_speed: " + YamlNumber(dn.per_speed) : "") +
             (dn.per_acceleration != 0 ? ", per_acceleration: " + YamlNumber(dn.per_acceleration) : "") +
             (dn.per_turn_rate != 0 ? ", per_turn_rate: " + YamlNumber(dn.per_turn_rate) : "") +
             (dn.simulated ? ", simulated: true" : "") +
             (dn.drift.any() ? ", drift: {" + AxisValues(dn.drift.sd) +
                                   ", correlation_time: " + YamlNumber(dn.drift.correlation_time) + "}"
                             : "") +
             "}",
         "m/s, rad/s, s: slip the wheels do not see", 46);
  }
  const OmniObserverModel& o = model.observer;
  if (o.process_noise != defaults.observer.process_noise || o.measurement_noise_xy > 0 ||
      o.measurement_noise_theta > 0 || !o.interval_scale.empty() || !o.seen_inputs.empty()) {
    s << "observer:\n";
    line("  process_noise", "{" + AxisValues(o.process_noise) + "}", "m/s and rad/s per sqrt(s): the model's own errors", 46);
    if (o.measurement_noise_xy > 0 || o.measurement_noise_theta > 0) {
      line("  measurement_noise",
           "{xy: " + YamlNumber(o.measurement_noise_xy) + ", theta: " + YamlNumber(o.measurement_noise_theta) + "}",
           "m, rad; 0 = the vision block's", 46);
    }
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
