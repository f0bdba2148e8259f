#include "robots/omni/omni_model_fields.h"

#include <stdexcept>
#include <type_traits>

namespace twinsim {
namespace {

// The get and set of one number of OmniModel (an int one is set rounded down, as the
// reader gives it a whole number).
#define TWINSIM_MODEL_NUMBER(member)                                   \
  [](const OmniModel& m) { return static_cast<double>(m.member); },    \
      [](OmniModel* m, double v) { m->member = static_cast<std::remove_reference_t<decltype(m->member)>>(v); }

// A PID section's six numbers (controller.forward, .sideways, .rotation), with its units.
#define TWINSIM_PID_FIELDS(axis, force, length)                                                                       \
  {"controller." #axis, "kp", force " per " length "/s", NonNegative(1e6), TWINSIM_MODEL_NUMBER(controller.axis.kp)}, \
      {"controller." #axis, "ki", force " per " length, NonNegative(1e6), TWINSIM_MODEL_NUMBER(controller.axis.ki)},  \
      {"controller." #axis, "kd", force " per " length "/s^2", NonNegative(1e6),                                     \
       TWINSIM_MODEL_NUMBER(controller.axis.kd)},                                                                     \
      {"controller." #axis, "integral_limit", force, NonNegative(1e6),                                              \
       TWINSIM_MODEL_NUMBER(controller.axis.integral_limit)},                                                         \
      {"controller." #axis, "output_limit", force, NonNegative(1e6), TWINSIM_MODEL_NUMBER(controller.axis.output_limit)}, \
      {"controller." #axis, "slew_rate", length "/s^2", NonNegative(1e6), TWINSIM_MODEL_NUMBER(controller.axis.slew_rate)}

// A key that is not one number: its place and unit only.
OmniModelField Custom(const char* section, const char* key, const char* unit) {
  OmniModelField f;
  f.section = section;
  f.key = key;
  f.unit = unit;
  f.custom = true;
  return f;
}

OmniModelField OmittedAtZero(OmniModelField f) {
  f.omitted_at_zero = true;
  return f;
}

OmniModelField Integer(OmniModelField f) {
  f.integer = true;
  return f;
}

std::vector<OmniModelField> MakeOmniModelFields() {
  return {
      // section, key, unit (the writer's comment), the reader's check, get and set
      {"chassis", "mass", "kg, without wheels", Positive(1000), TWINSIM_MODEL_NUMBER(chassis_mass)},
      {"chassis", "radius", "m", InRange(0.01, 10), TWINSIM_MODEL_NUMBER(chassis_radius)},
      {"chassis", "height", "m", Positive(10), TWINSIM_MODEL_NUMBER(chassis_height)},
      {"chassis", "inertia_z", "kg m^2; 0 = solid cylinder", NonNegative(1e4), TWINSIM_MODEL_NUMBER(chassis_inertia_z)},
      {"chassis", "com_height", "m above the floor", Positive(10), TWINSIM_MODEL_NUMBER(com_height)},
      Custom("chassis", "com", "m, the chassis' centre of mass from the centre, robot frame"),
      {"chassis", "ground_clearance", "m", NonNegative(1), TWINSIM_MODEL_NUMBER(ground_clearance)},
      OmittedAtZero({"chassis", "front_distance", "m, centre to the flat front", NonNegative(10),
                     TWINSIM_MODEL_NUMBER(front_distance)}),

      Custom("wheels", "angles_deg", "deg, from the robot's x axis"),
      {"wheels", "distance", "m, centre to wheel contact", InRange(0.001, 10), TWINSIM_MODEL_NUMBER(wheel_distance)},
      {"wheels", "radius", "m", Positive(1), TWINSIM_MODEL_NUMBER(wheel_radius)},
      {"wheels", "width", "m", Positive(1), TWINSIM_MODEL_NUMBER(wheel_width)},
      {"wheels", "mass", "kg each", Positive(100), TWINSIM_MODEL_NUMBER(wheel_mass)},
      {"wheels", "friction", "along the rolling direction", Positive(100), TWINSIM_MODEL_NUMBER(wheel_friction)},
      {"wheels", "roller_friction", "across the wheel", NonNegative(100), TWINSIM_MODEL_NUMBER(roller_friction)},
      {"wheels", "bearing_damping", "N·m per rad/s", NonNegative(1e3), TWINSIM_MODEL_NUMBER(bearing_damping)},

      {"motor", "stall_torque", "N·m at the wheel", Positive(1e4), TWINSIM_MODEL_NUMBER(motor_stall_torque)},
      {"motor", "no_load_speed", "rad/s at the wheel", Positive(1e5), TWINSIM_MODEL_NUMBER(motor_no_load_speed)},
      {"motor", "encoder_counts_per_rev", "counts; 0 = ideal encoder", NonNegative(1e9),
       TWINSIM_MODEL_NUMBER(encoder_counts_per_rev)},
      Custom("motor", "strength", "share of the stall torque, per wheel"),

      {"kicker", "max_speed", "m/s", InRange(0.1, 20), TWINSIM_MODEL_NUMBER(kicker_max_speed)},
      {"dribbler", "max_force", "N", InRange(0, 100), TWINSIM_MODEL_NUMBER(dribbler_max_force)},
      {"dribbler", "full_speed", "rpm", InRange(0, 1e5), TWINSIM_MODEL_NUMBER(dribbler_full_speed)},

      {"controller", "rate_hz", "Hz", InRange(1, 100000), TWINSIM_MODEL_NUMBER(controller.rate_hz)},
      TWINSIM_PID_FIELDS(forward, "N", "m"),
      TWINSIM_PID_FIELDS(sideways, "N", "m"),
      TWINSIM_PID_FIELDS(rotation, "N·m", "rad"),

      Integer({"delay", "command_frames", "camera frames", InRange(0, 100), TWINSIM_MODEL_NUMBER(command_delay_frames)}),
      Integer({"delay", "vision_frames", "camera frames", InRange(0, 100), TWINSIM_MODEL_NUMBER(vision_delay_frames)}),

      {"vision", "noise_xy", "m", NonNegative(10), TWINSIM_MODEL_NUMBER(vision_noise_xy)},
      {"vision", "noise_theta", "rad", NonNegative(10), TWINSIM_MODEL_NUMBER(vision_noise_theta)},
      {"vision", "drop_probability", "", InRange(0, 0.9), TWINSIM_MODEL_NUMBER(vision_drop_probability)},
      OmittedAtZero({"vision", "repeat_probability", "", InRange(0, 0.9), TWINSIM_MODEL_NUMBER(vision_repeat_probability)}),
      OmittedAtZero({"vision", "time_jitter", "s", InRange(0, 0.005), TWINSIM_MODEL_NUMBER(vision_time_jitter)}),

      {"driving_noise", "forward", "m/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.sd[0])},
      {"driving_noise", "sideways", "m/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.sd[1])},
      {"driving_noise", "turn", "rad/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.sd[2])},
      {"driving_noise", "correlation_time", "s", InRange(1e-3, 100), TWINSIM_MODEL_NUMBER(driving_noise.correlation_time)},
      OmittedAtZero({"driving_noise", "per_speed", "1/(m/s)", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.per_speed)}),
      OmittedAtZero({"driving_noise", "per_acceleration", "1/(m/s^2)", NonNegative(100),
                     TWINSIM_MODEL_NUMBER(driving_noise.per_acceleration)}),
      OmittedAtZero({"driving_noise", "per_turn_rate", "1/(rad/s)", NonNegative(100),
                     TWINSIM_MODEL_NUMBER(driving_noise.per_turn_rate)}),
      Custom("driving_noise", "simulated", ""),
      Custom("driving_noise", "drift", ""),
      {"driving_noise.drift", "forward", "m/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.drift.sd[0])},
      {"driving_noise.drift", "sideways", "m/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.drift.sd[1])},
      {"driving_noise.drift", "turn", "rad/s", NonNegative(100), TWINSIM_MODEL_NUMBER(driving_noise.drift.sd[2])},
      {"driving_noise.drift", "correlation_time", "s", InRange(0.1, 1000),
       TWINSIM_MODEL_NUMBER(driving_noise.drift.correlation_time)},

      {"observer.process_noise", "forward", "m/s per sqrt(s)", InRange(1e-6, 1e3),
       TWINSIM_MODEL_NUMBER(observer.process_noise[0])},
      {"observer.process_noise", "sideways", "m/s per sqrt(s)", InRange(1e-6, 1e3),
       TWINSIM_MODEL_NUMBER(observer.process_noise[1])},
      {"observer.process_noise", "turn", "rad/s per sqrt(s)", InRange(1e-6, 1e3),
       TWINSIM_MODEL_NUMBER(observer.process_noise[2])},
      {"observer.measurement_noise", "xy", "m", NonNegative(10), TWINSIM_MODEL_NUMBER(observer.measurement_noise_xy)},
      {"observer.measurement_noise", "theta", "rad", NonNegative(10), TWINSIM_MODEL_NUMBER(observer.measurement_noise_theta)},
  };
}

#undef TWINSIM_PID_FIELDS
#undef TWINSIM_MODEL_NUMBER

}  // namespace

const std::vector<OmniModelField>& OmniModelFields() {
  static const std::vector<OmniModelField> fields = MakeOmniModelFields();
  return fields;
}

std::vector<const OmniModelField*> OmniModelFieldsOf(const std::string& section) {
  std::vector<const OmniModelField*> out;
  for (const OmniModelField& f : OmniModelFields())
    if (f.section == section) out.push_back(&f);
  return out;
}

const OmniModelField& OmniModelFieldAt(const std::string& path) {
  for (const OmniModelField& f : OmniModelFields())
    if (f.path() == path) return f;
  throw std::logic_error("no omni model field '" + path + "'");
}

}  // namespace twinsim
