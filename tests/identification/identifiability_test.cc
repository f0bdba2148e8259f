// The identifiability analysis on sensitivity matrices whose answer is known.
#include "identification/identifiability.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/rng.h"

namespace twinsim {
namespace {

Eigen::MatrixXd RandomColumns(int rows, int cols, std::uint64_t seed) {
  Rng rng(seed);
  Eigen::MatrixXd j(rows, cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) j(r, c) = rng.Gaussian();
  return j;
}

// Independent sensitivities: everything kept, index near 1, and the covariance is the
// inverse normal matrix.
TEST(Identifiability, IndependentColumnsAreAllKept) {
  const Eigen::MatrixXd j = RandomColumns(400, 5, 3);
  const Identifiability id = AnalyseIdentifiability(j);
  EXPECT_EQ(id.kept.size(), 5u);
  EXPECT_TRUE(id.held.empty());
  EXPECT_LT(id.collinearity, 1.5);
  const Eigen::MatrixXd c = KeptInverseNormal(j, id.kept);
  ASSERT_EQ(c.rows(), 5);
  EXPECT_LT(((j.transpose() * j) * c - Eigen::MatrixXd::Identity(5, 5)).norm(), 1e-10);
}

// Column 3 = 2 col0 - col1 + a trace: parameters 0, 1 and 3 trade; one of them is held,
// the other two named as its partners, column 2 stays. Scaling a column does not change
// the answer (the index is on normalised columns).
TEST(Identifiability, ACombinationOfOthersIsHeldWithItsPartners) {
  Eigen::MatrixXd j = RandomColumns(300, 4, 5);
  j.col(3) = 2 * j.col(0) - j.col(1) + 1e-4 * j.col(2).cwiseAbs();
  for (double scale : {1.0, 1e6}) {
    Eigen::MatrixXd s = j;
    s.col(1) *= scale;
    const Identifiability id = AnalyseIdentifiability(s);
    ASSERT_EQ(id.held.size(), 1u) << scale;
    const HeldParameter& h = id.held[0];
    EXPECT_GT(h.collinearity, 1000);
    EXPECT_NE(h.column, 2);
    std::vector<int> trio = h.partners;
    trio.push_back(h.column);
    std::sort(trio.begin(), trio.end());
    EXPECT_EQ(trio, (std::vector<int>{0, 1, 3})) << scale;
    EXPECT_EQ(id.kept.size(), 3u);
    EXPECT_LE(id.collinearity, 20);
  }
}

// The preference decides which of two interchangeable parameters is held; a parameter
// the residuals ignore is held with no partners.
TEST(Identifiability, PreferenceChoosesAndIgnoredColumnsAreHeld) {
  Eigen::MatrixXd j = RandomColumns(200, 4, 8);
  j.col(1) = -j.col(0);
  j.col(3).setZero();
  const Identifiability a = AnalyseIdentifiability(j, {1, 3, 1, 1});
  const Identifiability b = AnalyseIdentifiability(j, {3, 1, 1, 1});
  ASSERT_EQ(a.held.size(), 2u);
  EXPECT_EQ(a.held[0].column, 3);
  EXPECT_TRUE(a.held[0].partners.empty());
  EXPECT_TRUE(std::isinf(a.held[0].collinearity));
  EXPECT_EQ(a.held[1].column, 1);
  EXPECT_EQ(a.held[1].partners, std::vector<int>{0});
  ASSERT_EQ(b.held.size(), 2u);
  EXPECT_EQ(b.held[1].column, 0);
  EXPECT_EQ(b.kept, (std::vector<int>{1, 2}));
  EXPECT_TRUE(KeptInverseNormal(j, {0, 1}).size() == 0);  // singular
}

// A strong but not hopeless collinearity (correlation 0.99 between two sensitivities:
// singular values sqrt(1 +- 0.99), index 10) is below the limit: both are kept and get
// (large) standard errors.
TEST(Identifiability, StrongCorrelationBelowTheLimitIsKept) {
  Eigen::MatrixXd j = RandomColumns(2000, 2, 11);
  j.col(1) = 0.99 * j.col(0) + std::sqrt(1 - 0.99 * 0.99) * j.col(1);
  const Identifiability id = AnalyseIdentifiability(j);
  EXPECT_TRUE(id.held.empty());
  EXPECT_NEAR(id.collinearity, 10, 1.5);
}

}  // namespace
}  // namespace twinsim
