#include "robots/arm/arm_dynamics.h"

#include <Eigen/Dense>
#include <cmath>

namespace twinsim {
namespace {

double Sign(double v) { return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0; }

// RNEA with gravity scaled by `g_scale` (0 drops gravity, for the mass matrix).
Eigen::VectorXd Rnea(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                     const Eigen::VectorXd& qdd, double g_scale) {
  const int n = model.dof();
  std::vector<Eigen::Matrix3d> r(static_cast<std::size_t>(n));   // R_{i-1 <- i}
  std::vector<Eigen::Vector3d> p(static_cast<std::size_t>(n));   // origin of i in i-1
  std::vector<Eigen::Vector3d> force(static_cast<std::size_t>(n)), moment(static_cast<std::size_t>(n));
  // Forward: velocities and accelerations of each link frame, in that frame. The base
  // accelerates upwards by -g, which adds gravity to every link.
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), dw = Eigen::Vector3d::Zero();
  Eigen::Vector3d a = -g_scale * model.gravity;
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d t = JointTransform(j, q[i]);
    const auto k = static_cast<std::size_t>(i);
    r[k] = t.linear();
    p[k] = t.translation();
    const Eigen::Matrix3d rt = r[k].transpose();
    // Acceleration of this frame's origin from the parent's motion.
    Eigen::Vector3d a_i = rt * (a + dw.cross(p[k]) + w.cross(w.cross(p[k])));
    Eigen::Vector3d w_i = rt * w, dw_i = rt * dw;
    const Eigen::Vector3d& z = j.axis;
    if (j.type == JointType::kRevolute) {
      dw_i += w_i.cross(z * qd[i]) + z * qdd[i];
      w_i += z * qd[i];
    } else {
      a_i += 2 * w_i.cross(z * qd[i]) + z * qdd[i];
    }
    w = w_i;
    dw = dw_i;
    a = a_i;
    const ArmLink& link = j.child;
    const Eigen::Vector3d a_c = a + dw.cross(link.com) + w.cross(w.cross(link.com));
    force[k] = link.mass * a_c;
    moment[k] = link.inertia * dw + w.cross(link.inertia * w) + link.com.cross(force[k]);
  }
  // Backward: each joint carries its link and everything beyond.
  Eigen::VectorXd tau(n);
  Eigen::Vector3d f = Eigen::Vector3d::Zero(), m = Eigen::Vector3d::Zero();
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    if (i + 1 < n) {
      const Eigen::Vector3d f_child = r[k + 1] * f;
      m = r[k + 1] * m + p[k + 1].cross(f_child);
      f = f_child;
    }
    f += force[k];
    m += moment[k];
    const ArmJoint& j = model.joints[k];
    tau[i] = j.type == JointType::kRevolute ? j.axis.dot(m) : j.axis.dot(f);
  }
  return tau;
}

}  // namespace

Eigen::Isometry3d JointTransform(const ArmJoint& j, double q) {
  Eigen::Isometry3d t = j.origin;
  if (j.type == JointType::kRevolute) {
    t.rotate(Eigen::AngleAxisd(q, j.axis));
  } else {
    t.translate(j.axis * q);
  }
  return t;
}

std::vector<Eigen::Isometry3d> ForwardKinematics(const ArmModel& model, const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> poses;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < model.dof(); ++i) {
    t = t * JointTransform(model.joints[static_cast<std::size_t>(i)], q[i]);
    poses.push_back(t);
  }
  return poses;
}

Eigen::VectorXd InverseDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, bool friction) {
  Eigen::VectorXd tau = Rnea(model, q, qd, qdd, 1.0);
  if (friction) {
    for (int i = 0; i < model.dof(); ++i) {
      const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
      tau[i] += j.viscous * qd[i] + j.coulomb * Sign(qd[i]);
    }
  }
  return tau;
}

Eigen::MatrixXd MassMatrix(const ArmModel& model, const Eigen::VectorXd& q) {
  const int n = model.dof();
  Eigen::MatrixXd m(n, n);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  for (int c = 0; c < n; ++c) m.col(c) = Rnea(model, q, zero, Eigen::VectorXd::Unit(n, c), 0.0);
  return 0.5 * (m + m.transpose());
}

Eigen::VectorXd BiasForces(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  return Rnea(model, q, qd, Eigen::VectorXd::Zero(model.dof()), 1.0);
}

Eigen::VectorXd ForwardDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, bool friction) {
  Eigen::VectorXd rhs = tau - BiasForces(model, q, qd);
  if (friction) {
    for (int i = 0; i < model.dof(); ++i) {
      const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
      rhs[i] -= j.viscous * qd[i] + j.coulomb * Sign(qd[i]);
    }
  }
  return MassMatrix(model, q).llt().solve(rhs);
}

double KineticEnergy(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  return 0.5 * qd.dot(MassMatrix(model, q) * qd);
}

double PotentialEnergy(const ArmModel& model, const Eigen::VectorXd& q) {
  const std::vector<Eigen::Isometry3d> poses = ForwardKinematics(model, q);
  double e = 0;
  for (int i = 0; i < model.dof(); ++i) {
    const ArmLink& link = model.joints[static_cast<std::size_t>(i)].child;
    e -= link.mass * model.gravity.dot(poses[static_cast<std::size_t>(i)] * link.com);
  }
  return e;
}

}  // namespace twinsim
