#include "analysis/fit_covariance.h"

#include <Eigen/Dense>

#include <algorithm>
#include <limits>

#include "analysis/clustered_standard_errors.h"

namespace twinsim {

namespace {

// Each coordinate's column among the free ones (-1: held, one of the first p in `held`),
// their count into *q.
std::vector<int> FreeColumns(int columns, int p, const std::vector<int>& held, int* q) {
  std::vector<int> place(static_cast<std::size_t>(columns), -1);
  *q = 0;
  for (int c = 0; c < columns; ++c)
    if (c >= p || std::find(held.begin(), held.end(), c) == held.end()) place[static_cast<std::size_t>(c)] = (*q)++;
  return place;
}

}  // namespace

std::vector<double> ClusteredStandardErrors(ceres::Problem* problem, const std::vector<double*>& blocks,
                                            const std::vector<ceres::ResidualBlockId>& residual_blocks, int p,
                                            const std::vector<int>& held,
                                            const std::vector<int>& cluster_of) {
  int labels = 0;
  const int clusters = ClustersWithRows(cluster_of, &labels);  // G: the clusters with rows
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
  int q = 0;
  const std::vector<int> place = FreeColumns(jacobian.num_cols, p, held, &q);
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
  const Eigen::VectorXd free_se = ClusteredStandardErrors(a, scores, clusters);
  std::vector<double> se(static_cast<std::size_t>(p), std::numeric_limits<double>::quiet_NaN());
  for (int c = 0; c < p && c < jacobian.num_cols; ++c) {
    const int k = place[static_cast<std::size_t>(c)];
    if (k >= 0) se[static_cast<std::size_t>(c)] = free_se[k];
  }
  return se;
}

}  // namespace twinsim
