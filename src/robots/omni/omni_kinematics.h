// Kinematics of an omni robot (seed 000, equation 1).
//
// Wheel speeds from a body velocity: w = (1/r) G v, with G the n x 3 geometry of
// omni_model.h (rows [-sin a_i, cos a_i, b]). Back by the pseudo-inverse:
// v = r (G^T G)^{-1} G^T w, the least-squares fit, which for four wheels averages out
// encoder errors that no rigid motion explains. The same matrices map a body wrench
// (Fx, Fy, Mz) to the least-norm wheel torques, tau = r G (G^T G)^{-1} F, which is how the
// on-board controller corrects "through wheel space".
#pragma once

#include <Eigen/Core>

#include "core/pose.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

class OmniKinematics {
 public:
  explicit OmniKinematics(const OmniModel& model);

  int num_wheels() const { return static_cast<int>(wheels_from_body_.rows()); }

  // Wheel speeds (rad/s) that roll without slip at body velocity v (robot frame).
  Eigen::VectorXd WheelSpeeds(const Twist2& v) const;
  // The body velocity (robot frame) that best explains the wheel speeds (least squares).
  Twist2 BodyVelocity(const Eigen::VectorXd& wheel_speeds) const;
  // The least-norm wheel torques (N·m) that produce the body wrench (N, N, N·m).
  Eigen::VectorXd WheelTorques(const Eigen::Vector3d& wrench) const;
  // The same into `out` (resized to n), without allocating once it has the size.
  void WheelTorques(const Eigen::Vector3d& wrench, Eigen::VectorXd* out) const;
  // The body wrench produced by wheel torques (N, N, N·m).
  Eigen::Vector3d Wrench(const Eigen::VectorXd& torques) const;

  const Eigen::MatrixXd& wheels_from_body() const { return wheels_from_body_; }  // n x 3, J
  const Eigen::MatrixXd& body_from_wheels() const { return body_from_wheels_; }  // 3 x n, J^+

 private:
  Eigen::MatrixXd wheels_from_body_;   // n x 3, G / r
  Eigen::MatrixXd body_from_wheels_;   // 3 x n, (J^T J)^{-1} J^T
  Eigen::MatrixXd torques_from_wrench_;  // n x 3, J (J^T J)^{-1}
};

}  // namespace twinsim
