#include "sim/ball_field.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/math_constants.h"

namespace twinsim {
namespace {

// The ball lies on the floor while its centre is this close to one radius up.
constexpr double kFloorGap = 5e-4;  // m
// The dribbler holds the ball on a spring to the point where it touches the front, at
// this natural frequency, critically damped, pulling with at most the robot's
// dribbler_max_force.
constexpr double kDribblerFrequency = 10;  // Hz

Eigen::Vector2d ToRobot(const Pose2& pose, const Eigen::Vector2d& p) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Eigen::Vector2d d = p - Eigen::Vector2d(pose.x, pose.y);
  return Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
}

}  // namespace

FrontContact BallAtFront(const BallModel& ball, const OmniModel& robot, const Pose2& pose, const BallState& state) {
  const Eigen::Vector2d p = ToRobot(pose, state.position.head<2>());
  const double front = robot.FrontDistance();
  const double half_width = robot.FrontHalfWidth();
  FrontContact c;
  c.gap = p.x() - front - ball.radius;
  c.lateral = p.y();
  c.on_front = std::abs(p.y()) <= half_width && p.x() > 0 && state.position.z() <= ball.radius + kFloorGap + 0.01;
  return c;
}

BallField::BallField(const BallModel& ball, std::vector<OmniModel> robots, const FieldModel& field,
                     std::unique_ptr<BallEngine> engine)
    : model_(ball), robots_(std::move(robots)), engine_(std::move(engine)) {
  std::string why;
  if (!ball.IsValid(&why)) throw std::invalid_argument("ball: " + why);
  if (!engine_) throw std::invalid_argument("BallField: no engine");
  engine_name_ = engine_->name();
  normal_gravity_ = std::abs(field.Gravity().z());
  state_.contact.assign(robots_.size(), false);
  state_.ball = engine_->GetBall();
}

void BallField::Reset(const BallState& state) {
  engine_->SetBall(state);
  state_.ball = engine_->GetBall();
  state_.contact.assign(robots_.size(), false);
  state_.pull.reset();
  kicks_.clear();
}

void BallField::Pull(const Eigen::Vector2d& target) { state_.pull = BallPull{target, kPullTimeout}; }

void BallField::AddPull() {
  const BallState& b = state_.ball;
  // F = 2 m w (v_want - v) with v_want = (w / 2) e: the spring m w^2 e and the damper
  // 2 m w v, critically damped, as long as neither limit is reached.
  const double omega = 2 * kPi * kPullFrequency;
  Eigen::Vector2d want = 0.5 * omega * (state_.pull->target - b.position.head<2>());
  if (want.norm() > kPullSpeed) want *= kPullSpeed / want.norm();
  Eigen::Vector2d force = 2 * model_.mass * omega * (want - b.velocity.head<2>());
  const double most = model_.mass * kPullAccel;
  if (force.norm() > most) force *= most / force.norm();
  engine_->AddBallForce(Eigen::Vector3d(force.x(), force.y(), 0), Eigen::Vector3d::Zero());
}

void BallField::Restore(const BallFieldState& state) {
  if (state.contact.size() != robots_.size()) throw std::invalid_argument("BallField::Restore: another field's state");
  engine_->SetBall(state.ball);
  state_ = state;
  kicks_.clear();
}

void BallField::AddResistance(double dt) {
  const BallState& b = state_.ball;
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  // Air drag, -1/2 rho C_d A |v| v.
  const double area = kPi * model_.radius * model_.radius;
  force -= 0.5 * kAirDensity * model_.drag * area * b.velocity.norm() * b.velocity;
  // Rolling resistance: a torque mu_r N r against the roll while the ball lies on the
  // floor (N its static weight across the floor), never more than stops the roll within
  // the step.
  if (b.position.z() <= model_.radius + kFloorGap) {
    const Eigen::Vector3d roll(b.spin.x(), b.spin.y(), 0);
    const double w = roll.norm();
    if (w > 0) {
      const double most = model_.inertia() * w / dt;
      const double tau = std::min(model_.rolling_friction * model_.mass * normal_gravity_ * model_.radius, most);
      torque -= tau / w * roll;
    }
  }
  engine_->AddBallForce(force, torque);
}

void BallField::StepFrame(const std::vector<Pose2>& from, const std::vector<Pose2>& to,
                          const std::vector<BallCommand>& commands, double frame_dt) {
  const std::size_t n = robots_.size();
  if (from.size() != n || to.size() != n || commands.size() != n)
    throw std::invalid_argument("BallField::StepFrame: one pose before, one after and one command per robot");
  if (!(frame_dt > 0)) throw std::invalid_argument("BallField::StepFrame: frame_dt must be > 0");
  const int steps = std::max(1, static_cast<int>(std::ceil(frame_dt / kMaxStep - 1e-9)));
  const double dt = frame_dt / steps;
  std::vector<Twist2> velocity(n);  // field frame
  for (std::size_t i = 0; i < n; ++i) {
    velocity[i] = Twist2{(to[i].x - from[i].x) / frame_dt, (to[i].y - from[i].y) / frame_dt,
                         WrapAngle(to[i].theta - from[i].theta) / frame_dt};
  }
  // Each frame starts from the ball's state alone (Bullet's contact caches cleared, ODE's
  // orientation of the sphere reset): so Restore() and stepping gives the same bytes as
  // stepping on from where the state was saved.
  engine_->SetBall(state_.ball);
  std::vector<bool> kicked(n, false);  // a kicker fires once a frame
  kicks_.assign(n, 0);
  for (int step = 0; step < steps; ++step) {
    const double t = step * dt;
    for (std::size_t i = 0; i < n; ++i) {
      const Pose2 pose{from[i].x + velocity[i].vx * t, from[i].y + velocity[i].vy * t,
                       from[i].theta + velocity[i].omega * t};
      engine_->SetRobot(static_cast<int>(i), pose, velocity[i]);
      const BallCommand& c = commands[i];
      if (c.kick_speed <= 0 && c.dribbler_speed <= 0) continue;
      const FrontContact at = BallAtFront(model_, robots_[i], pose, state_.ball);
      if (!at.on_front || at.gap > kReach) continue;
      const Eigen::Vector3d forward(std::cos(pose.theta), std::sin(pose.theta), 0);
      if (c.kick_speed > 0 && !kicked[i]) {
        // The kicker sets the ball's velocity: the speed commanded (up to the kicker's
        // limit) along the robot's heading, tilted up by the chip angle; no spin.
        const double speed = std::min(c.kick_speed, robots_[i].kicker_max_speed);
        BallState kick = state_.ball;
        kick.velocity = speed * (std::cos(c.kick_angle) * forward + std::sin(c.kick_angle) * Eigen::Vector3d::UnitZ());
        kick.spin.setZero();
        engine_->SetBall(kick);
        state_.ball = kick;
        kicked[i] = true;
        kicks_[i] = c.kick_angle > 0 ? 2 : 1;
        continue;
      }
      if (c.dribbler_speed > 0) {
        // A critically damped spring to where the ball touches the front, in the floor's
        // plane, capped at the dribbler's force.
        const double f = robots_[i].FrontDistance() + model_.radius;
        const Eigen::Vector3d hold(pose.x + f * forward.x(), pose.y + f * forward.y(), state_.ball.position.z());
        const Eigen::Vector3d hold_velocity(velocity[i].vx - velocity[i].omega * f * forward.y(),
                                            velocity[i].vy + velocity[i].omega * f * forward.x(), 0);
        const double omega = 2 * kPi * kDribblerFrequency;
        const double k = model_.mass * omega * omega, damping = 2 * model_.mass * omega;
        Eigen::Vector3d pull = k * (hold - state_.ball.position) + damping * (hold_velocity - state_.ball.velocity);
        pull.z() = 0;
        const OmniModel& robot = robots_[i];
        const double most = robot.dribbler_max_force *
                            (robot.dribbler_full_speed > 0 ? std::min(1.0, c.dribbler_speed / robot.dribbler_full_speed) : 1.0);
        if (pull.norm() > most) pull *= most / pull.norm();
        engine_->AddBallForce(pull, Eigen::Vector3d::Zero());
      }
    }
    AddResistance(dt);
    if (state_.pull) AddPull();
    engine_->Step(dt);
    state_.ball = engine_->GetBall();
  }
  if (state_.pull) {
    state_.pull->time_left -= frame_dt;
    const bool there = (state_.pull->target - state_.ball.position.head<2>()).norm() < kPullTolerance &&
                       state_.ball.velocity.head<2>().norm() < kPullStopSpeed;
    if (there || state_.pull->time_left <= 0) state_.pull.reset();
  }
  for (std::size_t i = 0; i < n; ++i) {
    const FrontContact at = BallAtFront(model_, robots_[i], to[i], state_.ball);
    state_.contact[i] = at.on_front && at.gap <= kTouch;
  }
}

}  // namespace twinsim
