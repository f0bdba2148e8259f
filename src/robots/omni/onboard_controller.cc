#include "robots/omni/onboard_controller.h"

#include <algorithm>
#include <cmath>

#include "core/math_constants.h"

namespace twinsim {

constexpr double kUnlimited = 1e300;

const PidGains& AxisGains(const OmniControllerModel& c, int axis) {
  return axis == 0 ? c.forward : axis == 1 ? c.sideways : c.rotation;
}

OnboardControllerState InitialControllerState(const OmniModel& model, const Twist2& v) {
  OnboardControllerState s;
  const int n = model.num_wheels();
  s.axes[0].setpoint = v.vx;
  s.axes[1].setpoint = v.vy;
  s.axes[2].setpoint = v.omega;
  s.wheel_angle.setZero(n);
  s.last_reading.setZero(n);
  s.torque_command.setZero(n);
  s.measured = v;
  return s;
}

void AccumulateEncoders(const Eigen::VectorXd& wheel_speeds, double dt, OnboardControllerState* s) {
  s->wheel_angle += wheel_speeds * dt;
}

namespace {
// An encoder's angle per count (rad); 0 for an ideal encoder.
double AnglePerCount(const OmniModel& model) {
  return model.encoder_counts_per_rev > 0 ? 2 * kPi / model.encoder_counts_per_rev : 0.0;
}

double Quantised(double wheel_angle, double per_count) {
  return per_count > 0 ? std::floor(wheel_angle / per_count) * per_count : wheel_angle;
}
}  // namespace

double EncoderReading(const OmniModel& model, double wheel_angle) {
  return Quantised(wheel_angle, AnglePerCount(model));
}

const Eigen::VectorXd& ControllerTick(const OmniModel& model, const OmniKinematics& kin,
                                      const Twist2& command, double dt,
                                      OnboardControllerState* s) {
  const int n = model.num_wheels();
  thread_local Eigen::VectorXd speeds;  // scratch: a tick runs a thousand times a simulated second
  speeds.resize(n);
  const double per_count = AnglePerCount(model);  // once a tick, not per wheel
  for (int i = 0; i < n; ++i) {
    const double reading = Quantised(s->wheel_angle[i], per_count);
    speeds[i] = (reading - s->last_reading[i]) / dt;
    s->last_reading[i] = reading;
  }
  s->measured = kin.BodyVelocity(speeds);

  const double cmd[3] = {command.vx, command.vy, command.omega};
  const double meas[3] = {s->measured.vx, s->measured.vy, s->measured.omega};
  Eigen::Vector3d wrench;
  for (int a = 0; a < 3; ++a) {
    const PidGains& g = AxisGains(model.controller, a);
    PidAxisState& st = s->axes[a];
    // A limit of 0 is no limit, as in the firmware: all zeros is a controller that does
    // nothing, not one that is frozen.
    const double max_step = g.slew_rate > 0 ? g.slew_rate * dt : kUnlimited;
    st.setpoint += std::clamp(cmd[a] - st.setpoint, -max_step, max_step);
    const double error = st.setpoint - meas[a];
    const double integral_limit = g.integral_limit > 0 ? g.integral_limit : kUnlimited;
    st.integral = std::clamp(st.integral + g.ki * error * dt, -integral_limit, integral_limit);
    const double derivative = g.kd * (error - st.last_error) / dt;
    st.last_error = error;
    const double output_limit = g.output_limit > 0 ? g.output_limit : kUnlimited;
    wrench[a] = std::clamp(g.kp * error + st.integral + derivative, -output_limit, output_limit);
  }
  kin.WheelTorques(wrench, &s->torque_command);
  return s->torque_command;
}

}  // namespace twinsim
