#include "backends/newtonian_omni_backend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "robots/omni/wheel_motor.h"

namespace twinsim {

int DefaultPhysicsSubsteps(double frame_rate) {
  return std::max(1, static_cast<int>(std::ceil(300.0 / frame_rate - 1e-9)));
}

NewtonianOmniBackend::NewtonianOmniBackend(std::unique_ptr<OmniEngine> engine,
                                           const std::vector<OmniModel>& robots,
                                           const FrameTiming& timing)
    : engine_(std::move(engine)), timing_(timing) {
  const double physics_rate = 1.0 / timing_.physics_dt();
  for (const auto& m : robots) {
    Robot r{m, OmniKinematics(m), 1, {}, Eigen::VectorXd::Zero(m.num_wheels()),
            Eigen::VectorXd::Zero(m.num_wheels())};
    const double ratio = physics_rate / m.controller.rate_hz;
    r.ticks_per_control = std::max(1, static_cast<int>(std::lround(ratio)));
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
  engine_->SetWheelTorques(robot, Eigen::VectorXd::Zero(r.model.num_wheels()));
}

void NewtonianOmniBackend::MoveBody(int robot, const Pose2& pose) {
  OmniBodyState body = engine_->GetState(robot);
  body.pose = pose;
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
      // One read per step: the encoders count the turn of the step just taken.
      engine_->GetWheelSpeeds(i, &r.speeds);
      if (r.state.encoders_pending) AccumulateEncoders(r.speeds, dt, &c);
      r.state.encoders_pending = true;
      if (r.state.ticks_until_control <= 0) {
        ControllerTick(r.model, r.kin, commands[static_cast<std::size_t>(i)],
                       dt * r.ticks_per_control, &c);
        r.state.ticks_until_control = r.ticks_per_control;
      }
      --r.state.ticks_until_control;
      for (int w = 0; w < r.speeds.size(); ++w)
        r.net[w] = WheelMotorTorque(r.model, c.torque_command[w], r.speeds[w]);
      engine_->SetWheelTorques(i, r.net);
    }
    engine_->Step(dt);
  }
}

Pose2 NewtonianOmniBackend::pose(int robot) const { return engine_->GetState(robot).pose; }
Twist2 NewtonianOmniBackend::velocity(int robot) const { return engine_->GetState(robot).velocity; }

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

std::vector<std::string> AvailableOmniBackends() { return AvailableOmniEngines(); }

std::unique_ptr<OmniBackend> MakeOmniBackend(const std::string& name,
                                             const std::vector<OmniModel>& robots,
                                             const FieldModel& field, const FrameTiming& timing) {
  return std::make_unique<NewtonianOmniBackend>(MakeOmniEngine(name, robots, field), robots, timing);
}

}  // namespace twinsim
