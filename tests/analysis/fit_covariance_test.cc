// The cluster-robust standard errors of a least-squares fit (analysis/fit_covariance.h)
// against the spread of the estimates themselves over many recordings.
#include "analysis/fit_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <vector>

#include "analysis/clustered_standard_errors.h"
#include "analysis/fixed_step_cost.h"

namespace twinsim {
namespace {

constexpr int kClusters = 20, kRows = 25;

// A line y = a + b t through kClusters stretches of kRows rows, each stretch's errors
// sharing a drawn offset (sd 0.5) besides their own (sd 0.1): rows within a stretch are
// far from independent.
struct Recording {
  std::vector<double> t, y;
  std::vector<int> cluster;
};

Recording Record(std::mt19937_64* rng) {
  std::normal_distribution<double> shared(0, 0.5), own(0, 0.1);
  Recording r;
  for (int c = 0; c < kClusters; ++c) {
    const double u = shared(*rng);
    for (int i = 0; i < kRows; ++i) {
      const double t = (c + (i + 0.5) / kRows) / kClusters;  // each stretch a piece of [0, 1]
      r.t.push_back(t);
      r.y.push_back(1.0 + 2.0 * t + u + own(*rng));
      r.cluster.push_back(c);
    }
  }
  return r;
}

// The line's fit (a, b) and their standard errors, with the rows grouped by `clusters`.
void Fit(const Recording& r, const std::vector<int>& clusters, std::vector<double>* x, std::vector<double>* se,
         const std::vector<int>& held = {}) {
  *x = {0.0, 0.0};
  ceres::Problem problem;
  const auto id = problem.AddResidualBlock(new FixedStepCost(r.t.size(), {1e-3, 1e-3},
                                                             [&r](const double* at, double* out) {
                                                               for (std::size_t i = 0; i < r.t.size(); ++i)
                                                                 out[i] = at[0] + at[1] * r.t[i] - r.y[i];
                                                               return true;
                                                             }),
                                           nullptr, x->data());
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  *se = ClusteredStandardErrors(&problem, {x->data()}, {id}, 2, held, clusters);
}

TEST(FitCovariance, ClusteredStandardErrorsMatchTheEstimatesSpreadWhereRowWiseOnesFallShort) {
  std::mt19937_64 rng(7);
  constexpr int kRecordings = 400;
  double sum[2] = {0, 0}, squares[2] = {0, 0}, clustered[2] = {0, 0}, row_wise[2] = {0, 0};
  std::vector<int> every_row(kClusters * kRows);
  for (std::size_t i = 0; i < every_row.size(); ++i) every_row[i] = static_cast<int>(i);
  for (int k = 0; k < kRecordings; ++k) {
    const Recording r = Record(&rng);
    std::vector<double> x, se, x_rows, se_rows;
    Fit(r, r.cluster, &x, &se);
    Fit(r, every_row, &x_rows, &se_rows);
    for (int p = 0; p < 2; ++p) {
      sum[p] += x[p];
      squares[p] += x[p] * x[p];
      clustered[p] += se[p] * se[p];
      row_wise[p] += se_rows[p] * se_rows[p];
    }
  }
  for (int p = 0; p < 2; ++p) {
    const double mean = sum[p] / kRecordings;
    const double spread = std::sqrt(squares[p] / kRecordings - mean * mean);
    const double said = std::sqrt(clustered[p] / kRecordings), said_by_rows = std::sqrt(row_wise[p] / kRecordings);
    std::printf("coordinate %d: mean %.4f, spread %.4f; clustered standard error %.4f, row-wise %.4f\n", p, mean,
                spread, said, said_by_rows);
    EXPECT_NEAR(mean, p == 0 ? 1.0 : 2.0, 3 * spread / std::sqrt(kRecordings));
    // The spread of 400 estimates is itself known to about 4 %; the sandwich with 20
    // clusters is a little low on average (its small-sample bias), hence 15 %.
    EXPECT_NEAR(said / spread, 1.0, 0.15) << p;
    // Rows taken one by one: the shared offsets are counted 25 times over.
    EXPECT_LT(said_by_rows, 0.5 * spread) << p;
  }
}

TEST(FitCovariance, AHeldCoordinateIsNaNAndAnUndeterminedOneInfinite) {
  std::mt19937_64 rng(3);
  Recording r = Record(&rng);
  std::vector<double> x, se;
  Fit(r, r.cluster, &x, &se, {1});
  EXPECT_TRUE(std::isfinite(se[0]));
  EXPECT_TRUE(std::isnan(se[1]));
  // Every row at t = 1: only a + b is determined.
  for (double& t : r.t) t = 1;
  Fit(r, r.cluster, &x, &se);
  EXPECT_TRUE(std::isinf(se[0]));
  EXPECT_TRUE(std::isinf(se[1]));
  // A single cluster says nothing of the spread between clusters.
  Fit(r, std::vector<int>(r.t.size(), 0), &x, &se);
  EXPECT_TRUE(se.empty());
}

// The same sandwich from a dense Jacobian (analysis/clustered_standard_errors.h, used where
// the residuals come from a simulation, as the omni drift's do): at the line's fit, J's
// rows (1, t_i) and the residuals give the Ceres problem's standard errors.
TEST(FitCovariance, ADenseJacobianGivesTheCeresProblemsStandardErrors) {
  std::mt19937_64 rng(11);
  const Recording r = Record(&rng);
  std::vector<double> x, se;
  Fit(r, r.cluster, &x, &se);
  Eigen::MatrixXd jacobian(static_cast<Eigen::Index>(r.t.size()), 2);
  Eigen::VectorXd residuals(static_cast<Eigen::Index>(r.t.size()));
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    jacobian(row, 0) = 1;
    jacobian(row, 1) = r.t[i];
    residuals[row] = x[0] + x[1] * r.t[i] - r.y[i];
  }
  const std::vector<double> dense = ClusteredStandardErrors(jacobian, residuals, {}, r.cluster);
  ASSERT_EQ(dense.size(), 2u);
  for (std::size_t p = 0; p < 2; ++p) EXPECT_NEAR(dense[p], se[p], 1e-6 * se[p]) << p;
  const std::vector<double> held = ClusteredStandardErrors(jacobian, residuals, {0}, r.cluster);
  ASSERT_EQ(held.size(), 2u);
  EXPECT_TRUE(std::isnan(held[0]));
  EXPECT_TRUE(std::isfinite(held[1]));
  EXPECT_TRUE(ClusteredStandardErrors(jacobian, residuals, {}, std::vector<int>(r.t.size(), 0)).empty());
}

}  // namespace
}  // namespace twinsim
