// A square root L of a covariance C (L L^T = C) for drawing from a Gaussian, scoring it
// or drawing its ellipses: from C's eigen-decomposition, V sqrt(max(0, lambda)), so a
// covariance that rounding left slightly indefinite is read as its positive part.
//
//   const Eigen::Matrix3d root = CovarianceRoot(covariance);
//   pose += root * z;  // z ~ N(0, I)
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace twinsim {

// The root of the symmetric part of `c` (N x N).
template <int N>
Eigen::Matrix<double, N, N> CovarianceRoot(const Eigen::Matrix<double, N, N>& c) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(0.5 * (c + c.transpose()));
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

}  // namespace twinsim
