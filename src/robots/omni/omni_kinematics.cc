#include "robots/omni/omni_kinematics.h"

#include <Eigen/Dense>

namespace twinsim {

OmniKinematics::OmniKinematics(const OmniModel& model) {
  wheels_from_body_ = model.geometry / model.wheel_radius;
  const Eigen::Matrix3d jtj = wheels_from_body_.transpose() * wheels_from_body_;
  const Eigen::Matrix3d jtj_inv = jtj.inverse();
  body_from_wheels_ = jtj_inv * wheels_from_body_.transpose();
  torques_from_wrench_ = wheels_from_body_ * jtj_inv;
}

Eigen::VectorXd OmniKinematics::WheelSpeeds(const Twist2& v) const {
  return wheels_from_body_ * Eigen::Vector3d(v.vx, v.vy, v.omega);
}

Twist2 OmniKinematics::BodyVelocity(const Eigen::VectorXd& wheel_speeds) const {
  // Coefficient by coefficient (lazyProduct): at 3 x n the general product's dispatch
  // costs more than its sums, and these run every physics step.
  const Eigen::Vector3d v = body_from_wheels_.lazyProduct(wheel_speeds);
  return Twist2{v[0], v[1], v[2]};
}

Eigen::VectorXd OmniKinematics::WheelTorques(const Eigen::Vector3d& wrench) const {
  return torques_from_wrench_ * wrench;
}

void OmniKinematics::WheelTorques(const Eigen::Vector3d& wrench, Eigen::VectorXd* out) const {
  out->resize(torques_from_wrench_.rows());
  out->noalias() = torques_from_wrench_.lazyProduct(wrench);
}

Eigen::Vector3d OmniKinematics::Wrench(const Eigen::VectorXd& torques) const {
  return wheels_from_body_.transpose().lazyProduct(torques);
}

}  // namespace twinsim
