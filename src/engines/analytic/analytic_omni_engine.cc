#include "engines/analytic/analytic_omni_engine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "robots/omni/omni_kinematics.h"

namespace twinsim {
namespace {

// Width of the regularised sign in the roller friction: below this sliding speed the
// friction force grows linearly (m/s).
constexpr double kRollerSlipScale = 1e-3;

struct AnalyticRobot {
  OmniModel model;
  OmniKinematics kin;
  Eigen::Matrix3d rigid_mass;    // M, about the centre
  Eigen::Matrix3d inverse_mass;  // (M + J^T I_w J)^{-1}
  Eigen::Matrix<double, 6, 1> x;  // x, y, theta, vx, vy, omega
  Eigen::VectorXd torques;        // n, N·m
  Eigen::Vector3d wrench;         // N, N, N·m: the torques' body wrench, J^T tau
  Eigen::Vector2d downhill;       // N, the weight's pull along a sloping floor (field frame)
  // Per wheel: the axle's direction (cos a_i, sin a_i), the rollers' friction limit and
  // the grip; fixed for a model, so the derivative spends no trigonometry on them.
  struct Wheel {
    double c, s, roller_limit, grip;
    double per_grip_squared;  // 1 / grip^2 (0 without grip), multiplied where a division costs more
  };
  std::vector<Wheel> wheels;

  AnalyticRobot(const OmniModel& m, const FieldModel& field) : model(m), kin(m) {
    downhill = m.total_mass * field.Gravity().head<2>();
    rigid_mass = m.RigidBodyMass();
    const Eigen::Matrix3d mass =
        rigid_mass + m.wheel_spin_inertia * kin.wheels_from_body().transpose() * kin.wheels_from_body();
    inverse_mass = mass.inverse();
    x.setZero();
    torques.setZero(m.num_wheels());
    wrench.setZero();
    for (int i = 0; i < m.num_wheels(); ++i) {
      const double grip = m.wheel_friction * m.wheel_load[i];
      wheels.push_back({std::cos(m.wheel_angles[i]), std::sin(m.wheel_angles[i]), m.roller_friction * m.wheel_load[i],
                        grip, grip > 0 ? 1 / (grip * grip) : 0});
    }
  }

  void SetTorques(const Eigen::VectorXd& t) {
    torques = t;
    wrench = kin.Wrench(torques);
  }

  Eigen::Matrix<double, 6, 1> Derivative(const Eigen::Matrix<double, 6, 1>& s) const {
    const double th = s[2], vx = s[3], vy = s[4], w = s[5];
    const Eigen::Vector3d p = rigid_mass * Eigen::Vector3d(vx, vy, w);
    Eigen::Vector3d force(w * p[1], -w * p[0], vy * p[0] - vx * p[1]);
    force += wrench;
    const double c = std::cos(th), sn = std::sin(th);
    // A sloping floor: the weight's share along it, at the centre of mass.
    if (!downhill.isZero()) {
      const Eigen::Vector2d f(c * downhill.x() + sn * downhill.y(), -sn * downhill.x() + c * downhill.y());
      force[0] += f.x();
      force[1] += f.y();
      force[2] += model.com_offset.x() * f.y() - model.com_offset.y() * f.x();
    }
    // Rollers: each wheel slides radially at (cos a, sin a) . v; the friction acts
    // along the axle, through the centre, so it makes no torque.
    for (const Wheel& wheel : wheels) {
      const double slip = wheel.c * vx + wheel.s * vy;
      const double f = -wheel.roller_limit * std::clamp(slip / kRollerSlipScale, -1.0, 1.0);
      force[0] += f * wheel.c;
      force[1] += f * wheel.s;
    }
    const Eigen::Vector3d acc = inverse_mass * force;
    Eigen::Matrix<double, 6, 1> d;
    d << c * vx - sn * vy, sn * vx + c * vy, w, acc;
    return d;
  }

  // The largest share of its grip (wheel_friction times its static load) a wheel needs
  // in state s with derivative ds: along the rolling direction the floor carries what
  // the motor's torque does not spend on the wheel's own spin, F_i = (tau_i - I_w
  // dw_i/dt) / r with dw/dt = J dv/dt; across it the rollers' friction.
  double GripNeeded(const Eigen::Matrix<double, 6, 1>& s, const Eigen::Matrix<double, 6, 1>& ds) const {
    const auto& j = kin.wheels_from_body();
    const double per_radius = 1 / model.wheel_radius;
    double worst = 0;  // the largest (force / grip)^2, its root taken once
    for (int i = 0; i < model.num_wheels(); ++i) {
      const Wheel& wheel = wheels[static_cast<std::size_t>(i)];
      if (wheel.grip <= 0) continue;
      const double spin = j(i, 0) * ds[3] + j(i, 1) * ds[4] + j(i, 2) * ds[5];
      const double rolling = (torques[i] - model.wheel_spin_inertia * spin) * per_radius;
      const double slip = wheel.c * s[3] + wheel.s * s[4];
      const double across = wheel.roller_limit * std::clamp(slip / kRollerSlipScale, -1.0, 1.0);
      worst = std::max(worst, (rolling * rolling + across * across) * wheel.per_grip_squared);
    }
    return std::sqrt(worst);
  }
};

class AnalyticOmniEngine final : public OmniEngine {
 public:
  AnalyticOmniEngine(const std::vector<OmniModel>& robots, const FieldModel& field) {
    for (const auto& m : robots) robots_.emplace_back(m, field);
  }

  std::string name() const override { return "analytic"; }
  int num_robots() const override { return static_cast<int>(robots_.size()); }

  void SetState(int robot, const OmniBodyState& state) override {
    AnalyticRobot& r = At(robot);
    r.x << state.pose.x, state.pose.y, state.pose.theta, state.velocity.vx, state.velocity.vy,
        state.velocity.omega;
  }

  OmniBodyState GetState(int robot) const override {
    const AnalyticRobot& r = robots_.at(static_cast<std::size_t>(Check(robot)));
    OmniBodyState s;
    s.pose = Pose2{r.x[0], r.x[1], r.x[2]};
    s.velocity = Twist2{r.x[3], r.x[4], r.x[5]};
    GetWheelSpeeds(robot, &s.wheel_speeds);
    return s;
  }

  Pose2 GetPose(int robot) const override {
    const AnalyticRobot& r = robots_.at(static_cast<std::size_t>(Check(robot)));
    return Pose2{r.x[0], r.x[1], r.x[2]};
  }

  Twist2 GetVelocity(int robot) const override {
    const AnalyticRobot& r = robots_.at(static_cast<std::size_t>(Check(robot)));
    return Twist2{r.x[3], r.x[4], r.x[5]};
  }

  // The wheels rolling with the body, J v, without allocating once `out` has the size.
  void GetWheelSpeeds(int robot, Eigen::VectorXd* out) const override {
    const AnalyticRobot& r = robots_.at(static_cast<std::size_t>(Check(robot)));
    out->resize(r.model.num_wheels());
    out->noalias() = r.kin.wheels_from_body().lazyProduct(r.x.tail<3>());
  }

  void SetWheelTorques(int robot, const Eigen::VectorXd& torques) override {
    AnalyticRobot& r = At(robot);
    if (torques.size() != r.model.num_wheels())
      throw std::invalid_argument("analytic engine: wrong number of wheel torques");
    r.SetTorques(torques);
  }

  GripCheck grip() const override { return grip_; }

  void Step(double dt) override {
    for (auto& r : robots_) {
      const auto& x = r.x;
      const auto k1 = r.Derivative(x);
      const double needed = r.GripNeeded(x, k1);
      ++grip_.steps;
      if (needed > 1) ++grip_.beyond;
      grip_.worst = std::max(grip_.worst, needed);
      const auto k2 = r.Derivative(x + 0.5 * dt * k1);
      const auto k3 = r.Derivative(x + 0.5 * dt * k2);
      const auto k4 = r.Derivative(x + dt * k3);
      r.x += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
  }

 private:
  int Check(int robot) const {
    if (robot < 0 || robot >= num_robots()) throw std::invalid_argument("analytic engine: no robot " + std::to_string(robot));
    return robot;
  }
  AnalyticRobot& At(int robot) { return robots_[static_cast<std::size_t>(Check(robot))]; }

  std::vector<AnalyticRobot> robots_;
  GripCheck grip_;
};

}  // namespace

std::unique_ptr<OmniEngine> MakeAnalyticOmniEngine(const std::vector<OmniModel>& robots,
                                                   const FieldModel& field) {
  return std::make_unique<AnalyticOmniEngine>(robots, field);
}

}  // namespace twinsim
