#include "robots/arm/arm_dynamics.h"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace twinsim {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

double Sign(double v) { return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0; }

// The joint's nominal friction torque (viscous and Coulomb) at qd.
double NominalFriction(const ArmJoint& j, double qd) { return j.viscous * qd + j.coulomb * Sign(qd); }

// Spatial vectors are (angular; linear), in a link's own frame about its origin
// (Featherstone's notation). A joint's motion subspace S is its axis in the angular half
// (revolute) or the linear half (prismatic): `Half` gives the offset of that half.
int Half(const ArmJoint& j) { return j.type == JointType::kRevolute ? 0 : 3; }

// Where joint j puts its link at q: r = R_{parent <- link}, p the link's origin in the
// parent's frame (JointTransform without the 4 x 4 product).
struct Placement {
  Eigen::Matrix3d r;
  Eigen::Vector3d p;
};

Placement Place(const ArmJoint& j, double q) {
  Placement x;
  if (j.type == JointType::kRevolute) {
    x.r.noalias() = j.origin.linear() * Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
    x.p = j.origin.translation();
  } else {
    x.r = j.origin.linear();
    x.p = j.origin.translation() + x.r * (j.axis * q);
  }
  return x;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// A link's spatial inertia about its frame's origin:
//   [I_c + m [c]x [c]x^T   m [c]x]
//   [m [c]x^T              m 1   ]
Matrix6d LinkInertia(const ArmLink& link) {
  const Eigen::Matrix3d cx = Skew(link.com);
  Matrix6d i;
  i.topLeftCorner<3, 3>() = link.inertia - link.mass * cx * cx;
  i.topRightCorner<3, 3>() = link.mass * cx;
  i.bottomLeftCorner<3, 3>() = -link.mass * cx;
  i.bottomRightCorner<3, 3>() = link.mass * Eigen::Matrix3d::Identity();
  return i;
}

// X^T I X for the motion transform X from parent to link: a symmetric 6 x 6 inertia
// (rigid or articulated) expressed in the parent's frame. In 3 x 3 blocks, rotated
// first and then shifted by p, about a third of the work of two 6 x 6 products.
Matrix6d InertiaToParent(const Matrix6d& in, const Placement& x) {
  const Eigen::Matrix3d& r = x.r;
  const Eigen::Matrix3d a = r * in.topLeftCorner<3, 3>() * r.transpose();
  const Eigen::Matrix3d b = r * in.topRightCorner<3, 3>() * r.transpose();
  const Eigen::Matrix3d c = r * in.bottomRightCorner<3, 3>() * r.transpose();
  const Eigen::Matrix3d px = Skew(x.p);
  const Eigen::Matrix3d pxc = px * c;
  const Eigen::Matrix3d pxbt = px * b.transpose();
  Matrix6d out;
  out.topLeftCorner<3, 3>() = a + pxbt + pxbt.transpose() - pxc * px;
  out.topRightCorner<3, 3>() = b + pxc;
  out.bottomLeftCorner<3, 3>() = out.topRightCorner<3, 3>().transpose();
  out.bottomRightCorner<3, 3>() = c;
  return out;
}

// X^T f: a force (moment; force) on the link, in the parent's frame about its origin.
Vector6d ForceToParent(const Vector6d& f, const Placement& x) {
  Vector6d out;
  out.tail<3>() = x.r * f.tail<3>();
  out.head<3>() = x.r * f.head<3>() + x.p.cross(out.tail<3>());
  return out;
}

// X m: a motion (angular; linear) of the parent, in the link's frame about its origin.
Vector6d MotionToLink(const Vector6d& m, const Placement& x) {
  Vector6d out;
  out.head<3>() = x.r.transpose() * m.head<3>();
  out.tail<3>() = x.r.transpose() * (m.tail<3>() + m.head<3>().cross(x.p));
  return out;
}

void CheckSizes(const ArmModel& model, const Eigen::VectorXd& q) {
  if (model.dof() > kMaxArmJoints) {
    throw std::invalid_argument("arm dynamics: " + std::to_string(model.dof()) + " joints; at most " +
                                std::to_string(kMaxArmJoints));
  }
  if (q.size() != model.dof()) throw std::invalid_argument("arm dynamics: q has the wrong size");
}

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

namespace {

// Featherstone's articulated-body algorithm (RBDA section 7.3, table 7.1) with the base
// accelerating by -g, so that gravity acts on every link. Per-link work lives on the
// stack (kMaxArmJoints entries), nothing is allocated; the per-model quantities (link
// inertias, joint placements) cost a few dozen flops and are formed here rather than
// cached, so that a changed model is never stale.
void ArticulatedBody(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                     const Eigen::VectorXd& tau, bool friction, Eigen::VectorXd* qdd) {
  const int n = model.dof();
  struct Link {
    Placement x;
    Matrix6d ia;   // articulated inertia
    Vector6d pa;   // articulated bias force
    Vector6d c;    // velocity-product acceleration v x S qd
    Vector6d u;    // U = I^A S
    double d;      // D = S^T U
    double force;  // tau - S^T p^A
  };
  std::array<Link, kMaxArmJoints> links;
  // Out: link velocities, the velocity-product terms and each link's own inertia and
  // bias force p = v x* I v.
  Vector6d v = Vector6d::Zero();
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    Link& l = links[static_cast<std::size_t>(i)];
    const int h = Half(j);
    l.x = Place(j, q[i]);
    v = MotionToLink(v, l.x);
    const Eigen::Vector3d s_qd = j.axis * qd[i];
    v.segment<3>(h) += s_qd;
    l.c.setZero();
    if (h == 0) {
      l.c.head<3>() = v.head<3>().cross(s_qd);
      l.c.tail<3>() = v.tail<3>().cross(s_qd);
    } else {
      l.c.tail<3>() = v.head<3>().cross(s_qd);
    }
    l.ia = LinkInertia(j.child);
    const Vector6d iv = l.ia * v;
    l.pa.head<3>() = v.head<3>().cross(iv.head<3>()) + v.tail<3>().cross(iv.tail<3>());
    l.pa.tail<3>() = v.head<3>().cross(iv.tail<3>());
  }
  // Back: each link hands its articulated inertia and bias, less what its joint
  // absorbs, to its parent.
  for (int i = n - 1; i >= 0; --i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    Link& l = links[static_cast<std::size_t>(i)];
    const int h = Half(j);
    l.u.noalias() = l.ia.middleCols<3>(h) * j.axis;
    l.d = j.axis.dot(l.u.segment<3>(h));
    l.force = tau[i] - j.axis.dot(l.pa.segment<3>(h));
    if (friction) l.force -= NominalFriction(j, qd[i]);
    if (i == 0) break;
    Link& parent = links[static_cast<std::size_t>(i - 1)];
    const Matrix6d ia = l.ia - l.u * (l.u.transpose() / l.d);
    const Vector6d pa = l.pa + ia * l.c + l.u * (l.force / l.d);
    parent.ia += InertiaToParent(ia, l.x);
    parent.pa += ForceToParent(pa, l.x);
  }
  // Out again: accelerations from the base's (-g) to the tip.
  qdd->resize(n);
  Vector6d a;
  a << Eigen::Vector3d::Zero(), -model.gravity;
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const Link& l = links[static_cast<std::size_t>(i)];
    a = MotionToLink(a, l.x) + l.c;
    const double qdd_i = (l.force - l.u.dot(a)) / l.d;
    a.segment<3>(Half(j)) += j.axis * qdd_i;
    (*qdd)[i] = qdd_i;
  }
}

}  // namespace

Eigen::VectorXd InverseDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, bool friction) {
  Eigen::VectorXd tau = Rnea(model, q, qd, qdd, 1.0);
  if (friction) {
    for (int i = 0; i < model.dof(); ++i) tau[i] += NominalFriction(model.joints[static_cast<std::size_t>(i)], qd[i]);
  }
  return tau;
}

Eigen::MatrixXd MassMatrix(const ArmModel& model, const Eigen::VectorXd& q) {
  Eigen::MatrixXd m;
  MassMatrix(model, q, &m);
  return m;
}

// The composite-rigid-body algorithm (RBDA section 6.2, table 6.2): the inertia of
// each link with everything beyond it, then each joint's column as the force its unit
// acceleration needs, carried towards the base.
void MassMatrix(const ArmModel& model, const Eigen::VectorXd& q, Eigen::MatrixXd* mass) {
  CheckSizes(model, q);
  const int n = model.dof();
  std::array<Placement, kMaxArmJoints> x;
  std::array<Matrix6d, kMaxArmJoints> composite;
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    x[static_cast<std::size_t>(i)] = Place(j, q[i]);
    composite[static_cast<std::size_t>(i)] = LinkInertia(j.child);
  }
  for (int i = n - 1; i > 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    composite[k - 1] += InertiaToParent(composite[k], x[k]);
  }
  mass->resize(n, n);
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    Vector6d f = composite[static_cast<std::size_t>(i)].middleCols<3>(Half(j)) * j.axis;
    (*mass)(i, i) = j.axis.dot(f.segment<3>(Half(j)));
    for (int k = i; k > 0; --k) {
      f = ForceToParent(f, x[static_cast<std::size_t>(k)]);
      const ArmJoint& parent = model.joints[static_cast<std::size_t>(k - 1)];
      (*mass)(k - 1, i) = (*mass)(i, k - 1) = parent.axis.dot(f.segment<3>(Half(parent)));
    }
  }
}

Eigen::MatrixXd MassMatrixReference(const ArmModel& model, const Eigen::VectorXd& q) {
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
  Eigen::VectorXd qdd;
  ForwardDynamics(model, q, qd, tau, friction, &qdd);
  return qdd;
}

void ForwardDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                     const Eigen::VectorXd& tau, bool friction, Eigen::VectorXd* qdd) {
  CheckSizes(model, q);
  if (qd.size() != model.dof() || tau.size() != model.dof()) {
    throw std::invalid_argument("arm dynamics: qd or tau has the wrong size");
  }
  ArticulatedBody(model, q, qd, tau, friction, qdd);
}

Eigen::VectorXd ForwardDynamicsReference(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                         const Eigen::VectorXd& tau, bool friction) {
  Eigen::VectorXd rhs = tau - BiasForces(model, q, qd);
  if (friction) {
    for (int i = 0; i < model.dof(); ++i) rhs[i] -= NominalFriction(model.joints[static_cast<std::size_t>(i)], qd[i]);
  }
  return MassMatrixReference(model, q).llt().solve(rhs);
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
