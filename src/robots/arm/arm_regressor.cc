#include "robots/arm/arm_regressor.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// I v = InertiaMap(v) [Ixx, Ixy, Ixz, Iyy, Iyz, Izz].
Eigen::Matrix<double, 3, 6> InertiaMap(const Eigen::Vector3d& v) {
  Eigen::Matrix<double, 3, 6> l;
  l << v.x(), v.y(), v.z(), 0, 0, 0,
       0, v.x(), 0, v.y(), v.z(), 0,
       0, 0, v.x(), 0, v.y(), v.z();
  return l;
}

double Sign(double v) { return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0; }

}  // namespace

Eigen::VectorXd StandardParameters(const ArmModel& model) {
  const int n = model.dof();
  Eigen::VectorXd pi((kParametersPerLink + kFrictionPerJoint) * n);
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const ArmLink& l = j.child;
    const Eigen::Vector3d mc = l.mass * l.com;
    // Inertia about the link frame's origin (parallel axes).
    const Eigen::Matrix3d io = l.inertia + l.mass * (l.com.squaredNorm() * Eigen::Matrix3d::Identity() - l.com * l.com.transpose());
    pi.segment<kParametersPerLink>(kParametersPerLink * i) << l.mass, mc.x(), mc.y(), mc.z(), io(0, 0), io(0, 1),
        io(0, 2), io(1, 1), io(1, 2), io(2, 2);
    pi[kParametersPerLink * n + kFrictionPerJoint * i] = j.viscous;
    pi[kParametersPerLink * n + kFrictionPerJoint * i + 1] = j.coulomb;
  }
  return pi;
}

std::vector<std::string> StandardParameterNames(const ArmModel& model) {
  static const char* kLink[] = {"m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  std::vector<std::string> names;
  for (int i = 1; i <= model.dof(); ++i)
    for (const char* p : kLink) names.push_back(p + std::to_string(i));
  for (int i = 1; i <= model.dof(); ++i) {
    names.push_back("fv" + std::to_string(i));
    names.push_back("fc" + std::to_string(i));
  }
  return names;
}

ArmModel WithStandardParameters(const ArmModel& model, const Eigen::VectorXd& pi) {
  ArmModel out = model;
  const int n = model.dof();
  for (int i = 0; i < n; ++i) {
    ArmJoint& j = out.joints[static_cast<std::size_t>(i)];
    const auto p = pi.segment<kParametersPerLink>(kParametersPerLink * i);
    if (!(p[0] > 0))
      throw InputError("link " + std::to_string(i + 1) + " would have a mass of " + std::to_string(p[0]) + " kg");
    j.child.mass = p[0];
    j.child.com = Eigen::Vector3d(p[1], p[2], p[3]) / p[0];
    Eigen::Matrix3d io;
    io << p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9];
    const Eigen::Vector3d& c = j.child.com;
    j.child.inertia = io - p[0] * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    j.viscous = pi[kParametersPerLink * n + kFrictionPerJoint * i];
    j.coulomb = pi[kParametersPerLink * n + kFrictionPerJoint * i + 1];
  }
  return out;
}

Eigen::MatrixXd Regressor(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& qdd) {
  const int n = model.dof();
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(n, (kParametersPerLink + kFrictionPerJoint) * n);
  std::vector<Eigen::Matrix3d> r(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> p(static_cast<std::size_t>(n));
  std::vector<Eigen::Matrix<double, 6, kParametersPerLink>> local(static_cast<std::size_t>(n));
  // Forward: link motions, as in the Newton-Euler recursion (arm_dynamics.cc).
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), dw = Eigen::Vector3d::Zero(), a = -model.gravity;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const ArmJoint& j = model.joints[k];
    const Eigen::Isometry3d t = JointTransform(j, q[i]);
    r[k] = t.linear();
    p[k] = t.translation();
    const Eigen::Matrix3d rt = r[k].transpose();
    Eigen::Vector3d a_i = rt * (a + dw.cross(p[k]) + w.cross(w.cross(p[k])));
    Eigen::Vector3d w_i = rt * w, dw_i = rt * dw;
    if (j.type == JointType::kRevolute) {
      dw_i += w_i.cross(j.axis * qd[i]) + j.axis * qdd[i];
      w_i += j.axis * qd[i];
    } else {
      a_i += 2 * w_i.cross(j.axis * qd[i]) + j.axis * qdd[i];
    }
    w = w_i;
    dw = dw_i;
    a = a_i;
    // The link's wrench about its origin, linear in [m, mc, I_o].
    Eigen::Matrix<double, 6, kParametersPerLink> l = Eigen::Matrix<double, 6, kParametersPerLink>::Zero();
    l.block<3, 1>(0, 0) = a;
    l.block<3, 3>(0, 1) = Skew(dw) + Skew(w) * Skew(w);
    l.block<3, 3>(3, 1) = -Skew(a);
    l.block<3, 6>(3, 4) = InertiaMap(dw) + Skew(w) * InertiaMap(w);
    local[k] = l;
  }
  // Backward: carry each link's wrench down the chain; joint j reads its axis' part.
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<double, 6, kParametersPerLink> wrench = local[static_cast<std::size_t>(i)];
    for (int j = i; j >= 0; --j) {
      const auto k = static_cast<std::size_t>(j);
      const ArmJoint& joint = model.joints[k];
      const auto row = joint.type == JointType::kRevolute ? joint.axis.transpose() * wrench.bottomRows<3>()
                                                          : joint.axis.transpose() * wrench.topRows<3>();
      y.block(j, kParametersPerLink * i, 1, kParametersPerLink) = row;
      if (j > 0) {
        const Eigen::Matrix<double, 3, kParametersPerLink> f = r[k] * wrench.topRows<3>();
        wrench.bottomRows<3>() = r[k] * wrench.bottomRows<3>() + Skew(p[k]) * f;
        wrench.topRows<3>() = f;
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    y(i, kParametersPerLink * n + kFrictionPerJoint * i) = qd[i];
    y(i, kParametersPerLink * n + kFrictionPerJoint * i + 1) = Sign(qd[i]);
  }
  return y;
}

Eigen::MatrixXd BaseParameters::Reduce(const Eigen::MatrixXd& y) const {
  Eigen::MatrixXd out(y.rows(), rank());
  for (int k = 0; k < rank(); ++k) out.col(k) = y.col(independent[static_cast<std::size_t>(k)]);
  return out;
}

BaseParameters FindBaseParameters(const ArmModel& model, int samples, std::uint64_t seed) {
  const int n = model.dof();
  const int cols = (kParametersPerLink + kFrictionPerJoint) * n;
  Rng rng = Rng::Derived(seed, 77);
  Eigen::MatrixXd w(samples * n, cols);
  Eigen::VectorXd q(n), qd(n), qdd(n);
  for (int s = 0; s < samples; ++s) {
    for (int i = 0; i < n; ++i) {
      const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
      const double lo = std::max(j.lower, -kPi), hi = std::min(j.upper, kPi);
      q[i] = rng.Uniform(lo, hi);
      qd[i] = rng.Uniform(-2, 2);
      qdd[i] = rng.Uniform(-5, 5);
    }
    w.middleRows(s * n, n) = Regressor(model, q, qd, qdd);
  }
  // Columns scaled to unit norm so that the rank threshold does not depend on units.
  Eigen::VectorXd norms = w.colwise().norm().transpose();
  BaseParameters base;
  const double largest = norms.maxCoeff();
  for (int c = 0; c < cols; ++c) {
    if (norms[c] <= 1e-10 * largest) {
      base.unidentifiable.push_back(c);
      norms[c] = 1;
    }
  }
  const Eigen::MatrixXd scaled = w * norms.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(scaled);
  qr.setThreshold(1e-8);
  const int rank = static_cast<int>(qr.rank());
  const Eigen::VectorXi perm = qr.colsPermutation().indices();
  const Eigen::MatrixXd r = qr.matrixR().topRows(rank).triangularView<Eigen::Upper>();
  // scaled * P = Q [R1 R2]: beta = pi_b + R1^{-1} R2 pi_d in scaled units.
  const Eigen::MatrixXd r1 = r.leftCols(rank).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd k = r1.triangularView<Eigen::Upper>().solve(r.rightCols(cols - rank));
  const std::vector<std::string> names = StandardParameterNames(model);
  base.from_standard = Eigen::MatrixXd::Zero(rank, cols);
  for (int b = 0; b < rank; ++b) {
    const int c = perm[b];
    base.independent.push_back(c);
    base.from_standard(b, c) = 1;
    std::ostringstream name;
    name << names[static_cast<std::size_t>(c)];
    for (int d = 0; d < cols - rank; ++d) {
      const int cd = perm[rank + d];
      // Undo the column scaling: coefficient on pi_d in the units of pi_b.
      const double coef = k(b, d) * norms[cd] / norms[c];
      if (std::abs(coef) < 1e-8) continue;
      base.from_standard(b, cd) = coef;
      name << (coef > 0 ? " + " : " - ") << std::abs(coef) << " " << names[static_cast<std::size_t>(cd)];
    }
    base.names.push_back(name.str());
  }
  return base;
}

}  // namespace twinsim
