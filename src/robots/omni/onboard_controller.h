// The robot's on-board velocity controller: three PID loops (forward, sideways,
// rotation) in the robot frame, running at the micro-controller's rate.
//
// Each tick it reads the wheel encoders, turns the wheel speeds into a body velocity by
// the pseudo-inverse (OmniKinematics), moves each set-point towards the command at most
// `slew_rate` per second, runs the three PIDs on the set-point error, and maps the
// resulting body wrench to wheel torques through wheel space. The model (gains) is
// const; everything that changes is in OnboardControllerState, a plain copyable value.
//
//   OnboardControllerState s = InitialControllerState(model, velocity);
//   per physics step:  AccumulateEncoders(model, wheel_speeds, dt, &s);
//   per controller tick:  torques = ControllerTick(model, kin, command, dt_tick, &s);
#pragma once

#include <Eigen/Core>
#include <array>

#include "core/pose.h"
#include "robots/omni/omni_kinematics.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

struct PidAxisState {
  double setpoint = 0;    // m/s or rad/s, the slew-limited command
  double integral = 0;    // N or N·m, the integral term (already multiplied by ki)
  double last_error = 0;  // m/s or rad/s
};

struct OnboardControllerState {
  std::array<PidAxisState, 3> axes;  // forward, sideways, rotation
  Eigen::VectorXd wheel_angle;       // n, rad, integrated wheel angle (the true shaft)
  Eigen::VectorXd last_reading;      // n, rad, encoder reading at the previous tick
  Eigen::VectorXd torque_command;    // n, N·m, held between ticks
  Twist2 measured;                   // robot frame, the last encoder-based estimate
};

// A controller settled at body velocity v: set-points on v, no integral, no torque.
OnboardControllerState InitialControllerState(const OmniModel& model, const Twist2& v);

// Advances the true wheel angles by one physics step of dt seconds.
void AccumulateEncoders(const Eigen::VectorXd& wheel_speeds, double dt, OnboardControllerState* s);

// The encoder reading (rad) of a true wheel angle: quantised to whole counts.
double EncoderReading(const OmniModel& model, double wheel_angle);

// One controller tick of dt seconds with the (already delayed) command; returns and
// stores the wheel torques (N·m) to hold until the next tick.
const Eigen::VectorXd& ControllerTick(const OmniModel& model, const OmniKinematics& kin,
                                      const Twist2& command, double dt,
                                      OnboardControllerState* s);

// The gains of axis 0 (forward), 1 (sideways) or 2 (rotation).
const PidGains& AxisGains(const OmniControllerModel& c, int axis);

}  // namespace twinsim
