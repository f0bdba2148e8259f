#include "robots/omni/omni_model_yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "io/atomic_file.h"

namespace twinsim {
namespace {

// Shortest text that reads back as the same double.
std::string Number(double v) {
  char buf[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

// An angle in degrees that the reader (deg * M_PI / 180.0) turns back into `rad`: the
// plain inverse can be an ulp off, so the doubles next to it are tried too, and the
// shortest exact one wins (57, not 57.000000000000007).
std::string Degrees(double rad) {
  double d = rad * 180.0 / M_PI;
  for (int i = 0; i < 8; ++i) d = std::nextafter(d, -INFINITY);
  std::string best;
  double best_error = INFINITY;
  for (int i = 0; i <= 16; ++i, d = std::nextafter(d, INFINITY)) {
    const double error = std::abs(d * M_PI / 180.0 - rad);
    const std::string text = Number(d);
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

std::string Pid(const PidGains& g) {
  return "{kp: " + Number(g.kp) + ", ki: " + Number(g.ki) + ", kd: " + Number(g.kd) +
         ", integral_limit: " + Number(g.integral_limit) + ", output_limit: " + Number(g.output_limit) +
         ", slew_rate: " + Number(g.slew_rate) + "}";
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
  s << "chassis:\n";
  line("  mass", Number(model.chassis_mass), "kg, without wheels");
  line("  radius", Number(model.chassis_radius), "m");
  line("  height", Number(model.chassis_height), "m");
  line("  inertia_z", Number(model.chassis_inertia_z), "kg m^2; 0 = solid cylinder");
  line("  com_height", Number(model.com_height), "m above the floor");
  line("  ground_clearance", Number(model.ground_clearance), "m");
  s << "wheels:\n";
  std::string angles;
  for (double a : model.wheel_angles) angles += (angles.empty() ? "" : ", ") + Degrees(a);
  line("  angles_deg", "[" + angles + "]", "deg, from the robot's x axis");
  line("  distance", Number(model.wheel_distance), "m, centre to wheel contact");
  line("  radius", Number(model.wheel_radius), "m");
  line("  width", Number(model.wheel_width), "m");
  line("  mass", Number(model.wheel_mass), "kg each");
  line("  friction", Number(model.wheel_friction), "along the rolling direction");
  line("  roller_friction", Number(model.roller_friction), "across the wheel");
  line("  bearing_damping", Number(model.bearing_damping), "N·m per rad/s");
  s << "motor:\n";
  line("  stall_torque", Number(model.motor_stall_torque), "N·m at the wheel");
  line("  no_load_speed", Number(model.motor_no_load_speed), "rad/s at the wheel");
  line("  encoder_counts_per_rev", Number(model.encoder_counts_per_rev), "counts; 0 = ideal encoder");
  s << "controller:\n";
  line("  rate_hz", Number(model.controller.rate_hz), "Hz");
  s << "  # kp N per m/s, ki N per m, kd N per m/s^2, limits N, slew_rate m/s^2\n"
       "  # (rotation: N·m and rad); a limit of 0 is no limit\n";
  line("  forward", Pid(model.controller.forward));
  line("  sideways", Pid(model.controller.sideways));
  line("  rotation", Pid(model.controller.rotation));
  s << "delay:\n";
  line("  command_frames", std::to_string(model.command_delay_frames), "camera frames");
  line("  vision_frames", std::to_string(model.vision_delay_frames), "camera frames");
  s << "vision:\n";
  line("  noise_xy", Number(model.vision_noise_xy), "m");
  line("  noise_theta", Number(model.vision_noise_theta), "rad");
  line("  drop_probability", Number(model.vision_drop_probability));

  // Only what is on, decided as OmniEffects::Active() decides it.
  const OmniEffects& fx = model.effects;
  const std::vector<std::string> active = fx.Active();
  auto on = [&active](const char* name) { return std::find(active.begin(), active.end(), name) != active.end(); };
  if (!active.empty()) {
    s << "effects:\n";
    if (on("time_delay")) line("  time_delay", "{delay: " + Number(fx.time_delay) + "}", "s", 46);
    if (on("velocity_saturation")) {
      std::string limits;
      if (fx.v_max > 0) limits += "v_max: " + Number(fx.v_max);
      if (fx.w_max > 0) limits += (limits.empty() ? "" : ", ") + std::string("w_max: ") + Number(fx.w_max);
      line("  velocity_saturation", "{" + limits + "}", "m/s, rad/s", 46);
    }
    if (on("motor_lag")) line("  motor_lag", "{time_constant: " + Number(fx.motor_lag) + "}", "s", 46);
    if (on("traction_limit")) line("  traction_limit", "{a_max: " + Number(fx.a_max) + "}", "m/s^2", 46);
    if (on("velocity_scale")) line("  velocity_scale", "{scale: " + Number(fx.velocity_scale) + "}", "times as fast", 46);
    if (on("rotation_drift")) line("  rotation_drift", "{rate: " + Number(fx.rotation_drift) + "}", "rad per metre", 46);
  }
  return s.str();
}

void WriteOmniModelYaml(const std::string& path, const OmniModel& model, const std::string& comment) {
  WriteFileAtomically(path, FormatOmniModelYaml(model, comment));
}

}  // namespace twinsim
