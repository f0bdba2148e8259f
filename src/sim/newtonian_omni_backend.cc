#include "sim/newtonian_omni_backend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "robots/omni/wheel_motor.h"

namespace twinsim {
namespace {
// x^2 + y^2 at most this share of a limit's square puts hypot(x, y) surely below the
// limit (rounding moves either by some 1e-16 of it).
constexpr double kSquaresBelow = 1 - 1e-6;
}  // namespace

std::unique_ptr<NewtonianOmniBackend> MakeNewtonianOmniBackend(const std::string& engine,
                                                               const std::vector<OmniModel>& robots,
                                                               const FieldModel& field, const FrameTiming& timing) {
  return std::make_unique<NewtonianOmniBackend>(MakeOmniEngine(engine, robots, field), robots, timing);
}

int DefaultPhysicsSubsteps(double frame_rate) {
  return std::max(1, static_cast<int>(std::ceil(300.0 / frame_rate - 1e-9)));
}

NewtonianOmniBackend::NewtonianOmniBackend(std::unique_ptr<OmniEngine> engine,
                                           const std::vector<OmniModel>& robots,
                                           const FrameTiming& timing)
    : engine_(std::move(engine)), timing_(timing) {
  const double physics_rate = 1.0 / timing_.physics_dt();
  for (const auto& m : robots) {
    Robot r{m, OmniKinematics(m), 1, m.effects.any(), {}, Eigen::VectorXd::Zero(m.num_wheels()),
            Eigen::VectorXd::Zero(m.num_wheels()), Eigen::VectorXd::Zero(m.num_wheels())};
    const double ratio = physics_rate / m.controller.rate_hz;
    r.ticks_per_control = std::max(1, static_cast<int>(std::lround(ratio)));
    r.index = static_cast<int>(robots_.size());
    auto share = [&](double t) { return t > 0 ? 1 - std::exp(-timing_.physics_dt() / t) : 0.0; };
    for (int a = 0; a < 3; ++a) {
      const double tau = m.effects.LagOf(a);
      r.lag_share[static_cast<std::size_t>(a)] = share(tau);
      r.lag_share_braking[static_cast<std::size_t>(a)] = share(tau * m.effects.lag_braking);
    }
    r.series_share = share(m.effects.lag_series);
    robots_.push_back(std::move(r));
  }
  for (int i = 0; i < num_robots(); ++i) Reset(i, Pose2{}, Twist2{});
}

void NewtonianOmniBackend::Reset(int robot, const Pose2& pose, const Twist2& velocity) {
  Robot& r = robots_.at(static_cast<std::size_t>(robot));
  OmniBodyState body;
  body.pose = pose;
  body.velocity = velocity;
  body.wheel_speeds = r.kin.WheelSpeeds(velocity);
  engine_->SetState(robot, body);
  r.state.body = body;
  r.state.controller = InitialControllerState(r.model, velocity);
  r.state.ticks_until_control = 0;
  r.state.encoders_pending = false;
  r.state.clock = 0;
  r.state.received.clear();
  r.state.acting = velocity;
  r.state.series_lagged = velocity;
  r.state.lagged = velocity;
  r.state.gripped = velocity;
  engine_->SetWheelTorques(robot, Eigen::VectorXd::Zero(r.model.num_wheels()));
}

void NewtonianOmniBackend::MoveBody(int robot, const Pose2& pose) { engine_->MoveRobot(robot, pose); }

void NewtonianOmniBackend::SetVelocity(int robot, const Twist2& velocity) {
  const Robot& r = robots_.at(static_cast<std::size_t>(robot));
  OmniBodyState body = engine_->GetState(robot);
  body.velocity = velocity;
  // The wheels roll with the body: the encoders read the corrected motion from now on.
  body.wheel_speeds = r.kin.WheelSpeeds(velocity);
  engine_->SetState(robot, body);
}

void NewtonianOmniBackend::StepFrame(const std::vector<Twist2>& commands) {
  if (static_cast<int>(commands.size()) != num_robots())
    throw std::invalid_argument("StepFrame: one command per robot expected");
  const double dt = timing_.physics_dt();
  for (int step = 0; step < timing_.physics_substeps; ++step) {
    for (int i = 0; i < num_robots(); ++i) {
      Robot& r = robots_[static_cast<std::size_t>(i)];
      OnboardControllerState& c = r.state.controller;
      const Twist2 command = EffectiveCommand(r, commands[static_cast<std::size_t>(i)], step == 0, dt);
      // One read per step: the encoders count the turn of the step just taken.
      engine_->GetWheelSpeeds(i, &r.speeds);
      if (r.state.encoders_pending) {
        if (r.effects_on) {
          r.seen = r.speeds;
          SeenWheelSpeeds(r, &r.seen);
          AccumulateEncoders(r.seen, dt, &c);
        } else {
          AccumulateEncoders(r.speeds, dt, &c);
        }
      }
      r.state.encoders_pending = true;
      if (r.state.ticks_until_control <= 0) {
        ControllerTick(r.model, r.kin, command, dt * r.ticks_per_control, &c);
        r.state.ticks_until_control = r.ticks_per_control;
      }
      --r.state.ticks_until_control;
      NetTorques(r);
      engine_->SetWheelTorques(i, r.net);
      r.state.clock += dt;
    }
    engine_->Step(dt);
  }
}

Twist2 NewtonianOmniBackend::EffectiveCommand(Robot& r, const Twist2& received, bool new_frame, double dt) {
  const OmniEffects& fx = r.model.effects;
  OmniRobotState& s = r.state;
  if (!r.effects_on) return received;
  if (new_frame) s.received.emplace_back(s.clock, received);
  // time_delay: the newest command received at least `delay` ago acts.
  std::size_t due = 0;
  while (due < s.received.size() && s.received[due].first + fx.time_delay <= s.clock + 1e-9) ++due;
  if (due > 0) {
    s.acting = s.received[due - 1].second;
    s.received.erase(s.received.begin(), s.received.begin() + static_cast<long>(due));
  }
  Twist2 c = s.acting;
  if (!s.received.empty()) {
    // A command that falls due within this step acts for the rest of it: the step sees
    // the time-weighted mean, so the response moves smoothly with the delay rather than
    // in whole physics steps (what a fit of the delay needs).
    const double after = s.clock + dt - (s.received.front().first + fx.time_delay);
    if (after > 1e-9) {
      const double u = std::min(1.0, after / dt);
      const Twist2& next = s.received.front().second;
      c = Twist2{c.vx + u * (next.vx - c.vx), c.vy + u * (next.vy - c.vy), c.omega + u * (next.omega - c.omega)};
    }
  }
  if (fx.MapsCommand()) {
    // velocity_scale per axis, cross_coupling and turn_coupling (omni_effects.h).
    const Twist2 a = c;
    c = Twist2{fx.axis_scale[0] * a.vx + fx.forward_per_sideways * a.vy,
               fx.axis_scale[1] * a.vy + fx.sideways_per_forward * a.vx,
               fx.axis_scale[2] * a.omega + fx.turn_per_forward * a.vx + fx.turn_per_sideways * a.vy +
                   fx.TurnByDirection(a.vx, a.vy)};
  }
  // hypot only near or over the limit (the squares' test is safe by far more than
  // their rounding): the same bytes as hypot every step, at a fraction of its cost.
  if (fx.v_max > 0 && c.vx * c.vx + c.vy * c.vy > kSquaresBelow * fx.v_max * fx.v_max) {
    const double speed = std::hypot(c.vx, c.vy);
    if (speed > fx.v_max) {
      c.vx *= fx.v_max / speed;
      c.vy *= fx.v_max / speed;
    }
  }
  if (fx.w_max > 0) c.omega = std::clamp(c.omega, -fx.w_max, fx.w_max);
  if (fx.AnyLag()) c = Lagged(r, c, dt);
  if (fx.a_max > 0) {
    // traction_limit: a slipping robot's wheels spin up to what the motors are driven
    // to while the body follows at the grip's acceleration, so the loop, reading the
    // wheels, sees its target approached at that pace. The translational set-point
    // changes by at most a_max dt (its length) per step, divided by the encoders' scale
    // (the body moves `scale` times the set-point); the loop follows it, and the
    // floor's force stays capped (NetTorques).
    const double dx = c.vx - s.gripped.vx, dy = c.vy - s.gripped.vy;
    const double most = fx.a_max * dt / fx.velocity_scale;
    if (dx * dx + dy * dy > kSquaresBelow * most * most) {
      const double change = std::hypot(dx, dy);
      if (change > most) c = Twist2{s.gripped.vx + dx * most / change, s.gripped.vy + dy * most / change, c.omega};
    }
  }
  s.gripped = c;
  return c;
}

Twist2 NewtonianOmniBackend::Lagged(Robot& r, Twist2 c, double dt) {
  const OmniEffects& fx = r.model.effects;
  OmniRobotState& s = r.state;
  if (r.series_share > 0) {
    // A lag in series before the axes' own: the command filtered once more, per axis
    // in the robot's frame.
    const double k = r.series_share;
    Twist2& u = s.series_lagged;
    u = Twist2{u.vx + k * (c.vx - u.vx), u.vy + k * (c.vy - u.vy), u.omega + k * (c.omega - u.omega)};
    c = u;
  }
  if (fx.lag_field_frame) {
    // The lagged translation keeps its direction in the field: in the robot's frame it
    // turns against the robot's own turn over the step.
    const double turn = -engine_->GetVelocity(r.index).omega * dt;
    const double cs = std::cos(turn), sn = std::sin(turn);
    s.lagged = Twist2{cs * s.lagged.vx - sn * s.lagged.vy, sn * s.lagged.vx + cs * s.lagged.vy, s.lagged.omega};
  }
  auto follow = [&](int axis, double lagged, double target) {
    // Slowing down (the set-point moves towards zero) at braking times the time constant.
    const bool braking = (target - lagged) * lagged < 0;
    const double share = (braking ? r.lag_share_braking : r.lag_share)[static_cast<std::size_t>(axis)];
    return share > 0 ? lagged + share * (target - lagged) : target;
  };
  s.lagged = Twist2{follow(0, s.lagged.vx, c.vx), follow(1, s.lagged.vy, c.vy), follow(2, s.lagged.omega, c.omega)};
  return s.lagged;
}

void NewtonianOmniBackend::SeenWheelSpeeds(Robot& r, Eigen::VectorXd* speeds) const {
  const OmniEffects& fx = r.model.effects;
  if (fx.velocity_scale == 1 && fx.rotation_drift == 0) return;
  // The firmware's wheel radius is off by `scale`, so every body velocity it measures is
  // `scale` times too small; and its yaw estimate is biased by `rate` per metre
  // travelled, so it drives the robot that much off.
  const Twist2 v = r.kin.BodyVelocity(*speeds);
  const double s = fx.velocity_scale;
  const double drift = fx.rotation_drift != 0 ? fx.rotation_drift * std::hypot(v.vx, v.vy) : 0.0;
  *speeds = r.kin.WheelSpeeds(Twist2{v.vx / s, v.vy / s, (v.omega - drift) / s});
}

void NewtonianOmniBackend::NetTorques(Robot& r) {
  const OnboardControllerState& c = r.state.controller;
  const Eigen::VectorXd* command = &c.torque_command;
  Eigen::VectorXd limited;
  if (r.model.effects.a_max > 0) {
    // traction_limit: the floor takes at most m * a_max of horizontal force.
    Eigen::Vector3d wrench = r.kin.Wrench(c.torque_command);
    const double limit = r.model.total_mass * r.model.effects.a_max;
    const double force = wrench[0] * wrench[0] + wrench[1] * wrench[1] > kSquaresBelow * limit * limit
                             ? std::hypot(wrench[0], wrench[1])
                             : 0.0;  // below the limit: not needed
    if (force > limit) {
      wrench.head<2>() *= limit / force;
      limited = r.kin.WheelTorques(wrench);
      command = &limited;
    }
  }
  for (int w = 0; w < r.speeds.size(); ++w) r.net[w] = WheelMotorTorque(r.model, w, (*command)[w], r.speeds[w]);
}

Pose2 NewtonianOmniBackend::pose(int robot) const { return engine_->GetPose(robot); }
Twist2 NewtonianOmniBackend::velocity(int robot) const { return engine_->GetVelocity(robot); }

OmniBackendState NewtonianOmniBackend::Save() const {
  OmniBackendState s;
  for (int i = 0; i < num_robots(); ++i) {
    OmniRobotState r = robots_[static_cast<std::size_t>(i)].state;
    r.body = engine_->GetState(i);
    r.engine_snapshot = engine_->SaveExact(i);
    s.robots.push_back(std::move(r));
  }
  return s;
}

void NewtonianOmniBackend::Restore(const OmniBackendState& state) {
  if (static_cast<int>(state.robots.size()) != num_robots())
    throw std::invalid_argument("Restore: state has the wrong number of robots");
  for (int i = 0; i < num_robots(); ++i) {
    Robot& r = robots_[static_cast<std::size_t>(i)];
    r.state = state.robots[static_cast<std::size_t>(i)];
    engine_->SetState(i, r.state.body);
    if (!r.state.engine_snapshot.empty()) engine_->RestoreExact(i, r.state.engine_snapshot);
  }
}

}  // namespace twinsim
