#include "engines/analytic/analytic_omni_engine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

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
  Eigen::Vector2d downhill;       // N, the weight's pull along a sloping floor (field frame)

  AnalyticRobot(const OmniModel& m, const FieldModel& field) : model(m), kin(m) {
    downhill = m.total_mass * field.Gravity().head<2>();
    rigid_mass = m.RigidBodyMass();
    const Eigen::Matrix3d mass =
        rigid_mass + m.wheel_spin_inertia * kin.wheels_from_body().transpose() * kin.wheels_from_body();
    inverse_mass = mass.inverse();
    x.setZero();
    torques.setZero(m.num_wheels());
  }

  Eigen::Matrix<double, 6, 1> Derivative(const Eigen::Matrix<double, 6, 1>& s) const {
    const double th = s[2], vx = s[3], vy = s[4], w = s[5];
    const Eigen::Vector3d p = rigid_mass * Eigen::Vector3d(vx, vy, w);
    Eigen::Vector3d force(w * p[1], -w * p[0], vy * p[0] - vx * p[1]);
    force += kin.Wrench(torques);
    // A sloping floor: the weight's share along it, at the centre of mass.
    if (!downhill.isZero()) {
      const double c = std::cos(th), sn = std::sin(th);
      const Eigen::Vector2d f(c * downhill.x() + sn * downhill.y(), -sn * downhill.x() + c * downhill.y());
      force[0] += f.x();
      force[1] += f.y();
      force[2] += model.com_offset.x() * f.y() - model.com_offset.y() * f.x();
    }
    // Rollers: each wheel slides radially at (cos a, sin a) . v; the friction acts
    // along the axle, through the centre, so it makes no torque.
    for (int i = 0; i < model.num_wheels(); ++i) {
      const double c = std::cos(model.wheel_angles[i]), sn = std::sin(model.wheel_angles[i]);
      const double slip = c * vx + sn * vy;
      const double f = -model.roller_friction * model.wheel_load[i] *
                       std::clamp(slip / kRollerSlipScale, -1.0, 1.0);
      force[0] += f * c;
      force[1] += f * sn;
    }
    const Eigen::Vector3d acc = inverse_mass * force;
    Eigen::Matrix<double, 6, 1> d;
    d << std::cos(th) * vx - std::sin(th) * vy, std::sin(th) * vx + std::cos(th) * vy, w, acc;
    return d;
  }

  // The largest share of its grip (wheel_friction times its static load) a wheel needs
  // in state s with derivative ds: along the rolling direction the floor carries what
  // the motor's torque does not spend on the wheel's own spin, F_i = (tau_i - I_w
  // dw_i/dt) / r with dw/dt = J dv/dt; across it the rollers' friction.
  double GripNeeded(const Eigen::Matrix<double, 6, 1>& s, const Eigen::Matrix<double, 6, 1>& ds) const {
    const Eigen::VectorXd spin = kin.wheels_from_body() * ds.tail<3>();
    double worst = 0;
    for (int i = 0; i < model.num_wheels(); ++i) {
      const double rolling = (torques[i] - model.wheel_spin_inertia * spin[i]) / model.wheel_radius;
      const double slip = std::cos(model.wheel_angles[i]) * s[3] + std::sin(model.wheel_angles[i]) * s[4];
      const double across = model.roller_friction * model.wheel_load[i] * std::clamp(slip / kRollerSlipScale, -1.0, 1.0);
      const double grip = model.wheel_friction * model.wheel_load[i];
      if (grip > 0) worst = std::max(worst, std::hypot(rolling, across) / grip);
    }
    return worst;
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
    s.wheel_speeds = r.kin.WheelSpeeds(s.velocity);
    return s;
  }

  void SetWheelTorques(int robot, const Eigen::VectorXd& torques) override {
    AnalyticRobot& r = At(robot);
    if (torques.size() != r.model.num_wheels())
      throw std::invalid_argument("analytic engine: wrong number of wheel torques");
    r.torques = torques;
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
