#include "identification/physical_consistency.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {
namespace {

constexpr int kLink = kParametersPerLink;

// Pseudo-inertia of one link's standard parameters [m, mcx, mcy, mcz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz].
Eigen::Matrix4d PseudoInertia(const Eigen::Ref<const Eigen::VectorXd>& p) {
  Eigen::Matrix3d i;
  i << p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9];
  Eigen::Matrix4d j = Eigen::Matrix4d::Zero();
  j.topLeftCorner<3, 3>() = 0.5 * i.trace() * Eigen::Matrix3d::Identity() - i;
  j.topRightCorner<3, 1>() = p.segment<3>(1);
  j.bottomLeftCorner<1, 3>() = p.segment<3>(1).transpose();
  j(3, 3) = p[0];
  return j;
}

Eigen::Matrix<double, kLink, 1> FromPseudoInertia(const Eigen::Matrix4d& j) {
  const Eigen::Matrix3d sigma = j.topLeftCorner<3, 3>();
  const Eigen::Matrix3d i = sigma.trace() * Eigen::Matrix3d::Identity() - sigma;
  Eigen::Matrix<double, kLink, 1> p;
  p << j(3, 3), j(0, 3), j(1, 3), j(2, 3), i(0, 0), i(0, 1), i(0, 2), i(1, 1), i(1, 2), i(2, 2);
  return p;
}

// A symmetric 4 x 4 matrix as 10 coordinates whose Euclidean norm is its Frobenius norm.
constexpr double kRoot2 = 1.4142135623730951;
Eigen::Matrix<double, kLink, 1> ToCoordinates(const Eigen::Matrix4d& s) {
  Eigen::Matrix<double, kLink, 1> y;
  y << s(0, 0), s(1, 1), s(2, 2), s(3, 3), kRoot2 * s(0, 1), kRoot2 * s(0, 2), kRoot2 * s(0, 3), kRoot2 * s(1, 2),
      kRoot2 * s(1, 3), kRoot2 * s(2, 3);
  return y;
}
Eigen::Matrix4d FromCoordinates(const Eigen::Ref<const Eigen::VectorXd>& y) {
  Eigen::Matrix4d s;
  s(0, 0) = y[0];
  s(1, 1) = y[1];
  s(2, 2) = y[2];
  s(3, 3) = y[3];
  s(0, 1) = s(1, 0) = y[4] / kRoot2;
  s(0, 2) = s(2, 0) = y[5] / kRoot2;
  s(0, 3) = s(3, 0) = y[6] / kRoot2;
  s(1, 2) = s(2, 1) = y[7] / kRoot2;
  s(1, 3) = s(3, 1) = y[8] / kRoot2;
  s(2, 3) = s(3, 2) = y[9] / kRoot2;
  return s;
}

// The coordinates y of standard parameters relative to the a-priori arm: per link the
// 10 coordinates of J' = J0^-1/2 J J0^-1/2, then friction divided by its a-priori value
// (1 where that is 0). pi = L y is linear; y = 1s (identity links, unit friction) is
// the a-priori arm.
struct Coordinates {
  int n = 0;
  std::vector<Eigen::Matrix4d> root;          // J0^1/2 per link
  std::vector<Eigen::Matrix4d> inverse_root;  // J0^-1/2 per link
  Eigen::VectorXd friction_scale;             // 2 n
  Eigen::MatrixXd l;                          // 12 n x 12 n: pi = L y

  Eigen::VectorXd ToStandard(const Eigen::VectorXd& y) const {
    Eigen::VectorXd pi(y.size());
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix4d j = root[static_cast<std::size_t>(i)] * FromCoordinates(y.segment<kLink>(kLink * i)) *
                                root[static_cast<std::size_t>(i)];
      pi.segment<kLink>(kLink * i) = FromPseudoInertia(j);
    }
    pi.tail(kFrictionPerJoint * n) = y.tail(kFrictionPerJoint * n).cwiseProduct(friction_scale);
    return pi;
  }
  Eigen::VectorXd FromStandard(const Eigen::VectorXd& pi) const {
    Eigen::VectorXd y(pi.size());
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix4d s = inverse_root[static_cast<std::size_t>(i)] * PseudoInertia(pi.segment<kLink>(kLink * i)) *
                                inverse_root[static_cast<std::size_t>(i)];
      y.segment<kLink>(kLink * i) = ToCoordinates(s);
    }
    y.tail(kFrictionPerJoint * n) = pi.tail(kFrictionPerJoint * n).cwiseQuotient(friction_scale);
    return y;
  }
  // The nearest consistent coordinates: each J' with eigenvalues at least `margin`,
  // friction not negative (the Euclidean projection onto that convex set).
  Eigen::VectorXd Project(const Eigen::VectorXd& y, double margin) const {
    Eigen::VectorXd out = y;
    for (int i = 0; i < n; ++i) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(FromCoordinates(y.segment<kLink>(kLink * i)));
      if (eig.eigenvalues().minCoeff() >= margin) continue;
      const Eigen::Vector4d lambda = eig.eigenvalues().cwiseMax(margin);
      out.segment<kLink>(kLink * i) =
          ToCoordinates(eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose());
    }
    out.tail(kFrictionPerJoint * n) = out.tail(kFrictionPerJoint * n).cwiseMax(0.0);
    return out;
  }
};

Coordinates MakeCoordinates(const ArmModel& a_priori) {
  Coordinates c;
  c.n = a_priori.dof();
  const Eigen::VectorXd pi0 = StandardParameters(a_priori);
  for (int i = 0; i < c.n; ++i) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(PseudoInertia(pi0.segment<kLink>(kLink * i)));
    if (!(eig.eigenvalues().minCoeff() > 0)) {
      throw InputError("the a-priori model's link " + std::to_string(i + 1) +
                       " is not physically consistent, so identification cannot start from it");
    }
    const Eigen::Vector4d root = eig.eigenvalues().cwiseSqrt();
    c.root.push_back(eig.eigenvectors() * root.asDiagonal() * eig.eigenvectors().transpose());
    c.inverse_root.push_back(eig.eigenvectors() * root.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose());
  }
  c.friction_scale = pi0.tail(kFrictionPerJoint * c.n);
  for (Eigen::Index k = 0; k < c.friction_scale.size(); ++k)
    if (!(c.friction_scale[k] > 0)) c.friction_scale[k] = 1;
  const int p = static_cast<int>(pi0.size());
  c.l.resize(p, p);
  for (int k = 0; k < p; ++k) c.l.col(k) = c.ToStandard(Eigen::VectorXd::Unit(p, k));
  return c;
}

}  // namespace

Eigen::VectorXd NearestStandardParameters(const ArmModel& a_priori, const Eigen::MatrixXd& k,
                                          const Eigen::VectorXd& beta) {
  const Coordinates c = MakeCoordinates(a_priori);
  const Eigen::VectorXd y0 = c.FromStandard(StandardParameters(a_priori));
  const Eigen::MatrixXd kl = k * c.l;
  return c.ToStandard(y0 + kl.completeOrthogonalDecomposition().solve(beta - kl * y0));
}

namespace {

// The log-det barrier of the consistent set, per link -log det(J' - margin 1), and
// -log f for each friction coordinate: its value, gradient and Hessian, or false when
// y is not strictly inside.
struct Barrier {
  int n = 0;
  double margin = 0;

  bool Evaluate(const Eigen::VectorXd& y, double* value, Eigen::VectorXd* gradient, Eigen::MatrixXd* hessian) const {
    const int p = static_cast<int>(y.size());
    if (gradient) gradient->setZero(p);
    if (hessian) hessian->setZero(p, p);
    double v = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix4d x = FromCoordinates(y.segment<kLink>(kLink * i)) - margin * Eigen::Matrix4d::Identity();
      const Eigen::LLT<Eigen::Matrix4d> llt(x);
      if (llt.info() != Eigen::Success) return false;
      const Eigen::Matrix4d l = llt.matrixL();
      if (!(l.diagonal().minCoeff() > 0)) return false;
      v -= 2 * l.diagonal().array().log().sum();
      if (!gradient && !hessian) continue;
      const Eigen::Matrix4d xi = llt.solve(Eigen::Matrix4d::Identity());
      // d/dy_k log det X = tr(X^-1 E_k), d2 = -tr(X^-1 E_k X^-1 E_l), E_k the coordinate's basis matrix.
      std::array<Eigen::Matrix4d, kLink> m;
      for (int k = 0; k < kLink; ++k) {
        Eigen::Matrix<double, kLink, 1> unit = Eigen::Matrix<double, kLink, 1>::Zero();
        unit[k] = 1;
        m[static_cast<std::size_t>(k)] = xi * FromCoordinates(unit);
      }
      for (int k = 0; k < kLink; ++k) {
        if (gradient) (*gradient)[kLink * i + k] = -m[static_cast<std::size_t>(k)].trace();
        if (hessian) {
          for (int j = 0; j <= k; ++j) {
            const double h = (m[static_cast<std::size_t>(k)] * m[static_cast<std::size_t>(j)]).trace();
            (*hessian)(kLink * i + k, kLink * i + j) = h;
            (*hessian)(kLink * i + j, kLink * i + k) = h;
          }
        }
      }
    }
    for (int k = kLink * n; k < p; ++k) {
      if (!(y[k] > 0)) return false;
      v -= std::log(y[k]);
      if (gradient) (*gradient)[k] = -1 / y[k];
      if (hessian) (*hessian)(k, k) = 1 / (y[k] * y[k]);
    }
    *value = v;
    return true;
  }
};

// The Newton step for gradient g and curvature d (all but the data term's) plus the data term's 2 t A'A, solved in
// (row space, null space) coordinates: the huge data curvature 2 t S^2 sits only in the row-space block, which is
// solved after eliminating the null-space block, each with diagonal scaling.
Eigen::VectorXd ConsistentNewtonStep(const Eigen::VectorXd& g, const Eigen::MatrixXd& d, double t,
                                     const Eigen::VectorXd& s2, const Eigen::MatrixXd& row_space,
                                     const Eigen::MatrixXd& null_space) {
  const bool has_null_space = null_space.cols() > 0;
  const Eigen::MatrixXd hvv = (2 * t * s2).asDiagonal().toDenseMatrix() + row_space.transpose() * d * row_space;
  const Eigen::MatrixXd hvw = row_space.transpose() * d * null_space;
  const Eigen::MatrixXd hww = null_space.transpose() * d * null_space;
  const Eigen::VectorXd gv = row_space.transpose() * g, gw = null_space.transpose() * g;
  Eigen::MatrixXd schur = hvv;
  Eigen::VectorXd rhs = -gv;
  Eigen::LDLT<Eigen::MatrixXd> ww;
  if (has_null_space) {
    ww.compute(hww);
    schur -= hvw * ww.solve(hvw.transpose());
    rhs += hvw * ww.solve(gw);
  }
  const Eigen::VectorXd scale = schur.diagonal().cwiseAbs().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
  const Eigen::VectorXd dv =
      scale.asDiagonal() * (scale.asDiagonal() * schur * scale.asDiagonal()).ldlt().solve(scale.asDiagonal() * rhs);
  Eigen::VectorXd delta = row_space * dv;
  if (has_null_space) delta += null_space * ww.solve(-gw - hvw.transpose() * dv);
  return delta;
}

// Backtracking along delta: stay strictly inside, then sufficient decrease (the quadratic parts' change computed
// exactly, not as a difference of large numbers); returns whether y moved.
bool BacktrackInside(const Barrier& barrier, const Eigen::MatrixXd& a, const Eigen::VectorXd& residual,
                     const Eigen::VectorXd& y0, double t, double pull, double value, double decrement,
                     const Eigen::VectorXd& delta, Eigen::VectorXd* y) {
  const Eigen::VectorXd a_delta = a * delta;
  double alpha = 1, candidate_value = 0;
  for (int halving = 0; halving < 60; ++halving, alpha *= 0.5) {
    const Eigen::VectorXd candidate = *y + alpha * delta;
    if (!barrier.Evaluate(candidate, &candidate_value, nullptr, nullptr)) continue;
    const double change = t * (2 * alpha * residual.dot(a_delta) + alpha * alpha * a_delta.squaredNorm()) +
                          pull * ((candidate - y0).squaredNorm() - (*y - y0).squaredNorm()) + candidate_value - value;
    if (change <= -0.25 * alpha * decrement) {
      *y = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace

ConsistentFit FitConsistentParameters(const ArmModel& a_priori, const Eigen::MatrixXd& k, const Eigen::MatrixXd& r,
                                      const Eigen::VectorXd& beta, const ConsistentFitOptions& options) {
  const Coordinates c = MakeCoordinates(a_priori);
  const int p = static_cast<int>(c.l.rows());
  const Eigen::VectorXd y0 = c.FromStandard(StandardParameters(a_priori));
  const Eigen::MatrixXd kl = k * c.l;
  // Data term ||A y - b||^2, A = R K L (r x p, rank r), b = R beta; with A = U S V^T the
  // row space P = V(:, 1..r) carries the data, the null space N = V(:, r+1..p) does not.
  const Eigen::MatrixXd a = r * kl;
  const Eigen::VectorXd b = r * beta;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const int rank = static_cast<int>(k.rows());
  const Eigen::MatrixXd row_space = svd.matrixV().leftCols(rank);
  const Eigen::MatrixXd null_space = svd.matrixV().rightCols(p - rank);
  const Eigen::VectorXd s2 = svd.singularValues().head(rank).cwiseAbs2();
  const Barrier barrier{c.n, options.margin};
  const double dims = 4.0 * c.n + kFrictionPerJoint * c.n;  // the barrier's degree

  // A strictly consistent start: the nearest parameters with K pi = beta, each link's
  // J' lifted to at least twice the margin, friction to at least 1e-3 of its scale.
  Eigen::VectorXd y = c.Project(y0 + kl.completeOrthogonalDecomposition().solve(beta - kl * y0), 2 * options.margin);
  y.tail(kFrictionPerJoint * c.n) = y.tail(kFrictionPerJoint * c.n).cwiseMax(1e-3);
  auto misfit = [&](const Eigen::VectorXd& v) { return (a * v - b).squaredNorm(); };

  // Barrier method: minimise t ||A y - b||^2 + pull ||y - y0||^2 + barrier(y) by Newton
  // steps for growing t; the data misfit is then within dims / t of the best consistent
  // one. Doubling t keeps each centring to a few Newton steps even when the answer lies
  // far from the a-priori model in these relative coordinates.
  ConsistentFit fit;
  double t = dims / std::max(misfit(y), 1e-300);
  for (int outer = 0; outer < 400; ++outer) {
    for (int step = 0; step < 100; ++step) {
      ++fit.iterations;
      double value = 0;
      Eigen::VectorXd gb;
      Eigen::MatrixXd hb;
      barrier.Evaluate(y, &value, &gb, &hb);
      const Eigen::VectorXd residual = a * y - b;
      const Eigen::VectorXd g = 2 * t * a.transpose() * residual + 2 * options.pull * (y - y0) + gb;
      const Eigen::MatrixXd d = hb + 2 * options.pull * Eigen::MatrixXd::Identity(p, p);
      const Eigen::VectorXd delta = ConsistentNewtonStep(g, d, t, s2, row_space, null_space);
      const double decrement = -g.dot(delta);
      if (!(decrement > 1e-10)) break;
      const bool moved = BacktrackInside(barrier, a, residual, y0, t, options.pull, value, decrement, delta, &y);
      if (!moved || decrement < 1e-9) break;
    }
    // Within dims / t of the best misfit, or the misfit itself that small.
    if (dims / t <= options.tolerance || misfit(y) <= options.tolerance) {
      fit.converged = true;
      break;
    }
    t *= 2;
  }
  fit.pi = c.ToStandard(y);
  fit.exact = (a * y - b).norm() <= 1e-3 * std::sqrt(static_cast<double>(rank));
  return fit;
}

}  // namespace twinsim
