#include "analysis/clustered_standard_errors.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace twinsim {

Eigen::VectorXd ClusteredStandardErrors(const Eigen::MatrixXd& a, const Eigen::MatrixXd& scores, int clusters) {
  const int q = static_cast<int>(a.rows());
  const Eigen::MatrixXd meat = scores * scores.transpose();

  // A's pseudo-inverse in A's own column scale, so that coordinates of different units
  // are judged alike; a direction it does not determine is infinitely uncertain.
  const Eigen::VectorXd d = a.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = d.asDiagonal() * a * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double floor = 1e-10 * std::max(lambda.maxCoeff(), std::numeric_limits<double>::min());
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(q);
  std::vector<bool> undetermined(static_cast<std::size_t>(q), false);
  for (int k = 0; k < q; ++k) {
    if (lambda[k] > floor) {
      inverse[k] = 1 / lambda[k];
      continue;
    }
    for (int c = 0; c < q; ++c)
      if (std::abs(eig.eigenvectors()(c, k)) > 1e-6) undetermined[static_cast<std::size_t>(c)] = true;
  }
  const Eigen::MatrixXd pinv =
      d.asDiagonal() * eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose() * d.asDiagonal();
  const Eigen::MatrixXd covariance =
      static_cast<double>(clusters) / (clusters - 1) * pinv * meat * pinv;
  Eigen::VectorXd se(q);
  for (int k = 0; k < q; ++k) {
    se[k] = undetermined[static_cast<std::size_t>(k)] ? std::numeric_limits<double>::infinity()
                                                      : std::sqrt(std::max(0.0, covariance(k, k)));
  }
  return se;
}

int ClustersWithRows(const std::vector<int>& cluster_of, int* labels) {
  *labels = cluster_of.empty() ? 0 : *std::max_element(cluster_of.begin(), cluster_of.end()) + 1;
  std::vector<bool> used(static_cast<std::size_t>(*labels), false);
  for (int c : cluster_of) used[static_cast<std::size_t>(c)] = true;
  return static_cast<int>(std::count(used.begin(), used.end(), true));
}

std::vector<double> ClusteredStandardErrors(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r,
                                            const std::vector<int>& held, const std::vector<int>& cluster_of) {
  int labels = 0;
  const int clusters = ClustersWithRows(cluster_of, &labels);
  if (clusters < 2 || r.size() != jacobian.rows() || static_cast<Eigen::Index>(cluster_of.size()) != r.size()) return {};
  const int p = static_cast<int>(jacobian.cols());
  std::vector<int> free;
  for (int c = 0; c < p; ++c)
    if (std::find(held.begin(), held.end(), c) == held.end()) free.push_back(c);
  const int q = static_cast<int>(free.size());
  Eigen::MatrixXd j(jacobian.rows(), q);
  for (int k = 0; k < q; ++k) j.col(k) = jacobian.col(free[static_cast<std::size_t>(k)]);
  Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(q, labels);
  for (Eigen::Index row = 0; row < j.rows(); ++row)
    scores.col(cluster_of[static_cast<std::size_t>(row)]) += j.row(row).transpose() * r[row];
  std::vector<double> se(static_cast<std::size_t>(p), std::numeric_limits<double>::quiet_NaN());
  if (q == 0) return se;
  const Eigen::VectorXd free_se = ClusteredStandardErrors(Eigen::MatrixXd(j.transpose() * j), scores, clusters);
  for (int k = 0; k < q; ++k) se[static_cast<std::size_t>(free[static_cast<std::size_t>(k)])] = free_se[k];
  return se;
}

}  // namespace twinsim
