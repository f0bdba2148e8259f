#include "analysis/fit_covariance.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinsim {

std::vector<double> ClusteredStandardErrors(ceres::Problem* problem, const std::vector<double*>& blocks,
                                            const std::vector<ceres::ResidualBlockId>& residual_blocks, int p,
                                            const std::vector<int>& held,
                                            const std::vector<int>& cluster_of) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> se(static_cast<std::size_t>(p), nan);
  const int labels = cluster_of.empty() ? 0 : *std::max_element(cluster_of.begin(), cluster_of.end()) + 1;
  std::vector<bool> used(static_cast<std::size_t>(labels), false);
  for (int c : cluster_of) used[static_cast<std::size_t>(c)] = true;
  const auto clusters = static_cast<int>(std::count(used.begin(), used.end(), true));  // G: the clusters with rows
  if (clusters < 2) return {};
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  options.residual_blocks = residual_blocks;
  options.num_threads = 1;
  std::vector<double> r;
  ceres::CRSMatrix jacobian;
  double cost = 0;
  if (!problem->Evaluate(options, &cost, &r, nullptr, &jacobian) || r.size() != cluster_of.size()) return {};

  // The free columns (held ones out) and their place in A.
  std::vector<int> place(static_cast<std::size_t>(jacobian.num_cols), -1);
  int q = 0;
  for (int c = 0; c < jacobian.num_cols; ++c)
    if (c >= p || std::find(held.begin(), held.end(), c) == held.end()) place[static_cast<std::size_t>(c)] = q++;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(q, q);
  Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(q, labels);  // column c: g_c (0 for a label without rows)
  for (int row = 0; row < jacobian.num_rows; ++row) {
    auto score = scores.col(cluster_of[static_cast<std::size_t>(row)]);
    const int begin = jacobian.rows[static_cast<std::size_t>(row)], end = jacobian.rows[static_cast<std::size_t>(row) + 1];
    for (int i = begin; i < end; ++i) {
      const int ci = place[static_cast<std::size_t>(jacobian.cols[static_cast<std::size_t>(i)])];
      if (ci < 0) continue;
      const double vi = jacobian.values[static_cast<std::size_t>(i)];
      score[ci] += vi * r[static_cast<std::size_t>(row)];
      for (int k = begin; k < end; ++k) {
        const int ck = place[static_cast<std::size_t>(jacobian.cols[static_cast<std::size_t>(k)])];
        if (ck >= 0) a(ci, ck) += vi * jacobian.values[static_cast<std::size_t>(k)];
      }
    }
  }
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
  for (int c = 0; c < p && c < jacobian.num_cols; ++c) {
    const int k = place[static_cast<std::size_t>(c)];
    if (k < 0) continue;
    se[static_cast<std::size_t>(c)] = undetermined[static_cast<std::size_t>(k)]
                                          ? std::numeric_limits<double>::infinity()
                                          : std::sqrt(std::max(0.0, covariance(k, k)));
  }
  return se;
}

}  // namespace twinsim
