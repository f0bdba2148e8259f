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

// Spatial vectors are (angular; linear) (Featherstone's notation): a motion (w; v_O), a
// force (n_O; f), about a point O.

// Where joint j puts its link at q: r = R_{parent <- link}, p the link's origin in the
// parent's frame (JointTransform without the 4 x 4 product).
struct Placement {
  Eigen::Matrix3d r;
  Eigen::Vector3d p;
};

Placement Place(const ArmJoint& j, double q) {
  Placement x;
  if (j.type == JointType::kRevolute && j.axis == Eigen::Vector3d::UnitZ()) {
    // The common axis (every DH joint, most URDF ones): R_origin Rot(z, q) mixes two
    // columns, a quarter of the general product's work.
    const double c = std::cos(q), s = std::sin(q);
    const Eigen::Matrix3d o = j.origin.linear();
    x.r.col(0) = c * o.col(0) + s * o.col(1);
    x.r.col(1) = c * o.col(1) - s * o.col(0);
    x.r.col(2) = o.col(2);
    x.p = j.origin.translation();
  } else if (j.type == JointType::kRevolute) {
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

// The fast algorithms work in the base frame (Featherstone's spatial vectors about the
// base origin, base axes; RBDA section 7.3's "in absolute coordinates"): a rigid
// link's inertia is expressed there once, an articulated or composite inertia is
// handed to the parent by a plain sum, and no 6 x 6 inertia is ever transformed from
// frame to frame. Per link: its pose, its joint's motion subspace S and its inertia.
struct WorldLink {
  Eigen::Matrix3d r;  // R_{base <- link}
  Eigen::Vector3d p;  // m: the link frame's origin
  Vector6d s;         // the joint's motion subspace: (a; p x a) revolute, (0; a) prismatic
  Matrix6d inertia;   // about the base origin
};

// The spatial inertia about the base origin of a link with centre of mass c and
// rotational inertia I_c (both in base axes):
//   [I_c + m [c]x [c]x'   m [c]x]
//   [m [c]x'              m 1   ]
// with [c]x [c]x' = (c . c) 1 - c c'.
void SetWorldInertia(const ArmLink& link, WorldLink* w) {
  const Eigen::Vector3d c = w->p + w->r * link.com;
  const Eigen::Matrix3d cx = Skew(c);
  w->inertia.topLeftCorner<3, 3>().noalias() = w->r * link.inertia * w->r.transpose();
  w->inertia.topLeftCorner<3, 3>().diagonal().array() += link.mass * c.squaredNorm();
  w->inertia.topLeftCorner<3, 3>().noalias() -= (link.mass * c) * c.transpose();
  w->inertia.topRightCorner<3, 3>() = link.mass * cx;
  w->inertia.bottomLeftCorner<3, 3>() = -link.mass * cx;
  w->inertia.bottomRightCorner<3, 3>() = link.mass * Eigen::Matrix3d::Identity();
}

// Poses, motion subspaces and inertias of every link at q (forward kinematics).
template <typename Links>
void PlaceLinks(const ArmModel& model, const Eigen::VectorXd& q, Links* links) {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < model.dof(); ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    WorldLink& w = (*links)[static_cast<std::size_t>(i)];
    const Placement x = Place(j, q[i]);
    w.p = p + r * x.p;
    w.r.noalias() = r * x.r;
    const Eigen::Vector3d axis = w.r * j.axis;
    if (j.type == JointType::kRevolute) {
      w.s << axis, w.p.cross(axis);
    } else {
      w.s << Eigen::Vector3d::Zero(), axis;
    }
    SetWorldInertia(j.child, &w);
    r = w.r;
    p = w.p;
  }
}

// v x m for spatial motions (crm): (w x m_w; w x m_v + v x m_w). This and CrossForce
// are forced inline: as calls that pass 6-vectors through memory they cost a fifth of
// the articulated-body algorithm (measured; forcing more inline measured slower).
EIGEN_ALWAYS_INLINE Vector6d CrossMotion(const Vector6d& v, const Vector6d& m) {
  Vector6d out;
  out << v.head<3>().cross(m.head<3>()), v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>());
  return out;
}

// v x* f for a spatial force (crf): (w x n + v x f; w x f).
EIGEN_ALWAYS_INLINE Vector6d CrossForce(const Vector6d& v, const Vector6d& f) {
  Vector6d out;
  out << v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>()), v.head<3>().cross(f.tail<3>());
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
  CheckSizes(model, q);
  const int n = model.dof();
  std::array<Eigen::Matrix3d, kMaxArmJoints> r;  // R_{i-1 <- i}
  std::array<Eigen::Vector3d, kMaxArmJoints> p;  // origin of i in i-1
  std::array<Eigen::Vector3d, kMaxArmJoints> force, moment;
  // Forward: velocities and accelerations of each link frame, in that frame. The base
  // accelerates upwards by -g, which adds gravity to every link.
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), dw = Eigen::Vector3d::Zero();
  Eigen::Vector3d a = -g_scale * model.gravity;
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const auto k = static_cast<std::size_t>(i);
    const Placement x = Place(j, q[i]);
    r[k] = x.r;
    p[k] = x.p;
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

// Featherstone's articulated-body algorithm (RBDA section 7.3, table 7.1) in the base
// frame, with the base accelerating by -g so that gravity acts on every link. Per-link
// work lives on the stack (kMaxArmJoints entries): nothing is allocated. The links'
// poses and inertias in base coordinates (under a hundred multiply-adds per link) are
// formed on every call, from the model as it is: there is no cache to go stale.
void ArticulatedBody(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                     const Eigen::VectorXd& tau, bool friction, Eigen::VectorXd* qdd) {
  const int n = model.dof();
  struct Link : WorldLink {
    Vector6d c;    // velocity-product acceleration v x S qd
    Vector6d pa;   // articulated bias force
    Vector6d u;    // U = I^A S
    double d;      // D = S^T U
    double force;  // tau - S^T p^A (- friction)
  };
  std::array<Link, kMaxArmJoints> links;
  PlaceLinks(model, q, &links);
  // Out: link velocities, the velocity-product terms and each link's bias force
  // p = v x* I v; `inertia` becomes the articulated inertia I^A on the way back.
  Vector6d v = Vector6d::Zero();
  for (int i = 0; i < n; ++i) {
    Link& l = links[static_cast<std::size_t>(i)];
    const Vector6d s_qd = l.s * qd[i];
    v += s_qd;
    l.c = CrossMotion(v, s_qd);
    l.pa = CrossForce(v, l.inertia * v);
  }
  // Back: each link hands its articulated inertia and bias, less what its joint
  // absorbs, to its parent; in base coordinates that is a sum.
  for (int i = n - 1; i >= 0; --i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    Link& l = links[static_cast<std::size_t>(i)];
    l.u.noalias() = l.inertia * l.s;
    l.d = l.s.dot(l.u);
    l.force = tau[i] - l.s.dot(l.pa);
    if (friction) l.force -= NominalFriction(j, qd[i]);
    if (i == 0) break;
    Link& parent = links[static_cast<std::size_t>(i - 1)];
    l.inertia.noalias() -= l.u * (l.u.transpose() / l.d);
    parent.inertia += l.inertia;
    parent.pa += l.pa + l.inertia * l.c + l.u * (l.force / l.d);
  }
  // Out again: accelerations from the base's (0; -g) to the tip.
  qdd->resize(n);
  Vector6d a;
  a << Eigen::Vector3d::Zero(), -model.gravity;
  for (int i = 0; i < n; ++i) {
    const Link& l = links[static_cast<std::size_t>(i)];
    a += l.c;
    const double qdd_i = (l.force - l.u.dot(a)) / l.d;
    a += l.s * qdd_i;
    (*qdd)[i] = qdd_i;
  }
}

// The composite-rigid-body algorithm (RBDA section 6.2, table 6.2) in the base frame:
// the inertia of each link with everything beyond it is a sum there, and joint i's
// column is the force F = I^C_i S_i its unit acceleration needs, which every joint
// between it and the base feels unchanged: M_ji = S_j' F. With `qd`, also the bias
// C(q, qd) qd + g(q) by Newton-Euler on the same placements (RBDA table 5.1): each
// link needs f = I a + v x* I v at qdd = 0, and joint i carries the sum beyond it.
void CompositeRigidBody(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd* qd,
                        Eigen::MatrixXd* mass, Eigen::VectorXd* bias) {
  CheckSizes(model, q);
  const int n = model.dof();
  std::array<WorldLink, kMaxArmJoints> links;
  PlaceLinks(model, q, &links);
  if (qd) {
    std::array<Vector6d, kMaxArmJoints> force;
    Vector6d v = Vector6d::Zero(), a;
    a << Eigen::Vector3d::Zero(), -model.gravity;
    for (int i = 0; i < n; ++i) {
      const WorldLink& l = links[static_cast<std::size_t>(i)];
      const Vector6d s_qd = l.s * (*qd)[i];
      v += s_qd;
      a += CrossMotion(v, s_qd);
      force[static_cast<std::size_t>(i)] = l.inertia * a + CrossForce(v, l.inertia * v);
    }
    bias->resize(n);
    for (int i = n - 1; i >= 0; --i) {
      if (i + 1 < n) force[static_cast<std::size_t>(i)] += force[static_cast<std::size_t>(i + 1)];
      (*bias)[i] = links[static_cast<std::size_t>(i)].s.dot(force[static_cast<std::size_t>(i)]);
    }
  }
  mass->resize(n, n);
  for (int i = n - 1; i >= 0; --i) {
    WorldLink& l = links[static_cast<std::size_t>(i)];
    if (i + 1 < n) l.inertia += links[static_cast<std::size_t>(i + 1)].inertia;
    const Vector6d f = l.inertia * l.s;
    for (int k = 0; k <= i; ++k) (*mass)(k, i) = (*mass)(i, k) = links[static_cast<std::size_t>(k)].s.dot(f);
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

void MassMatrix(const ArmModel& model, const Eigen::VectorXd& q, Eigen::MatrixXd* mass) {
  CompositeRigidBody(model, q, nullptr, mass, nullptr);
}

void MassMatrixAndBias(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                       Eigen::MatrixXd* mass, Eigen::VectorXd* bias) {
  if (qd.size() != model.dof()) throw std::invalid_argument("arm dynamics: qd has the wrong size");
  CompositeRigidBody(model, q, &qd, mass, bias);
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
