// The ridge's cross-validation and the choice of outputs by a fold cost
// (learning/cross_validated_ridge.h), on data made here with known answers.
#include "learning/cross_validated_ridge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

namespace twinsim {
namespace {

// 400 rows of 6 inputs in 4 folds of 100; output 0 is a linear function of the inputs
// plus a little noise, output 1 noise alone.
struct Data {
  Eigen::MatrixXd x, y;
  std::vector<int> fold;
};

Data MakeData() {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  Data d;
  d.x.resize(400, 6);
  d.y.resize(400, 2);
  const Eigen::VectorXd b = (Eigen::VectorXd(6) << 1.0, -0.5, 0.25, 0.0, 2.0, -1.0).finished();
  for (long i = 0; i < 400; ++i) {
    for (long j = 0; j < 6; ++j) d.x(i, j) = n(rng);
    d.y(i, 0) = d.x.row(i).dot(b) + 0.1 * n(rng);
    d.y(i, 1) = n(rng);
    d.fold.push_back(static_cast<int>(i / 100));
  }
  return d;
}

TEST(CrossValidatedRidge, KeepsTheOutputWithSignalAndNoFitOfNoise) {
  const Data d = MakeData();
  const std::vector<double> r = ChooseRidgesByOneStandardError(d.x, d.y, d.fold, {1e-4, 1e-2, 1.0});
  EXPECT_TRUE(std::isfinite(r[0]));
  EXPECT_TRUE(std::isinf(r[1])) << "noise alone: predicting zero is within one standard error";
}

// The held-out fold's squared prediction error, both outputs: the cost that ranks the
// subsets of outputs fitted. With output 1's noise fitted anyway (a finite ridge forced),
// the choice drops it and keeps output 0, and its costs are the folds' means.
TEST(ChooseOutputsByFoldCost, DropsTheOutputWhoseFitMakesTheCostWorse) {
  const Data d = MakeData();
  int calls = 0;
  const FoldCost held_out = [&](int k, const Eigen::VectorXd& scale,
                                const Eigen::MatrixXd& w) -> std::optional<double> {
    ++calls;
    EXPECT_EQ(w.rows(), 2);
    EXPECT_EQ(w.cols(), 6);
    double sum = 0;
    int n = 0;
    for (long i = 0; i < d.x.rows(); ++i) {
      if (d.fold[static_cast<std::size_t>(i)] != k) continue;
      const Eigen::VectorXd z = d.x.row(i).transpose().cwiseQuotient(scale);
      sum += (d.y.row(i).transpose() - w * z).squaredNorm();
      ++n;
    }
    return sum / n;
  };
  const OutputSubsetChoice c = ChooseOutputsByFoldCost(d.x, d.y, d.fold, {1e-4, 1e-4}, held_out);
  EXPECT_EQ(calls, 4 * 4);  // four folds, four subsets
  EXPECT_EQ(c.folds, 4);
  EXPECT_EQ(c.chosen, 3);
  EXPECT_EQ(c.kept, 1);
  EXPECT_LT(c.cost_kept, c.cost_chosen);
  // The physics alone (no output fitted) costs the outputs' whole variance: about
  // |b|^2 = 6.3125 plus the noise's 1.
  EXPECT_NEAR(c.cost_none, 7.3, 1.0);
  EXPECT_NEAR(c.cost_kept, 1.0, 0.15);  // output 1's unit noise, output 0's 0.01
}

TEST(ChooseOutputsByFoldCost, KeepsEveryOutputWhereFewerThanTwoFoldsAreScored) {
  const Data d = MakeData();
  const FoldCost one_fold = [](int k, const Eigen::VectorXd&, const Eigen::MatrixXd& w) -> std::optional<double> {
    if (k != 0) return std::nullopt;
    return w.squaredNorm();
  };
  const double inf = std::numeric_limits<double>::infinity();
  const OutputSubsetChoice c = ChooseOutputsByFoldCost(d.x, d.y, d.fold, {1e-2, inf}, one_fold);
  EXPECT_EQ(c.folds, 1);
  EXPECT_EQ(c.chosen, 1);
  EXPECT_EQ(c.kept, 1) << "not checked: kept as chosen";
  const OutputSubsetChoice none = ChooseOutputsByFoldCost(d.x, d.y, d.fold, {inf, inf}, one_fold);
  EXPECT_EQ(none.chosen, 0);
  EXPECT_EQ(none.kept, 0);
  EXPECT_EQ(none.folds, 0);
}

}  // namespace
}  // namespace twinsim
