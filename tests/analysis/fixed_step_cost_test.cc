// Numeric derivatives at fixed steps (analysis/fixed_step_cost.h) on a cost that is
// jagged at fine scales, as a replay's is (encoder counts, controller ticks).
#include "analysis/fixed_step_cost.h"

#include <gtest/gtest.h>

#include <cmath>

namespace twinsim {
namespace {

// r(x) = the value x quantised to 1e-4, minus 0.5: a staircase whose least squares lie
// at x = 0.5.
bool Staircase(const double* x, double* r) {
  r[0] = std::round(x[0] / 1e-4) * 1e-4 - 0.5;
  return true;
}

struct StaircaseFunctor {
  bool operator()(double const* const* x, double* r) const { return Staircase(x[0], r); }
};

double SolveFrom(double start, ceres::CostFunction* cost) {
  double x = start;
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, &x);
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  options.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return x;
}

TEST(FixedStepCost, AFitStartingAtZeroMovesOnAJaggedCost) {
  // A fixed step of 0.01 sees the staircase's slope, 1, from x = 0.
  EXPECT_NEAR(SolveFrom(0.0, new FixedStepCost(1, {0.01}, Staircase)), 0.5, 1e-3);
  // Ceres' own numeric derivatives take 1.5e-8 at x = 0 whatever the relative step: a
  // flat stair, a zero derivative, and the fit ends where it started (the omni
  // diagnosis's couplings and drifts started there, issue 44).
  ceres::NumericDiffOptions diff;
  diff.relative_step_size = 2e-2;
  auto* ceres_cost =
      new ceres::DynamicNumericDiffCostFunction<StaircaseFunctor, ceres::CENTRAL>(new StaircaseFunctor, ceres::TAKE_OWNERSHIP, diff);
  ceres_cost->AddParameterBlock(1);
  ceres_cost->SetNumResiduals(1);
  EXPECT_EQ(SolveFrom(0.0, ceres_cost), 0.0);
}

TEST(FixedStepCost, CentralDifferencesOfALinearMapAreItsMatrix) {
  const auto linear = [](const double* x, double* r) {
    r[0] = 2 * x[0] - x[1];
    r[1] = 0.5 * x[1];
    r[2] = x[0] + 3 * x[1];
    return true;
  };
  const double x[2] = {0.3, -7};
  double j[6];
  ASSERT_TRUE(CentralDifferences(linear, x, {1e-3, 0.5}, 3, j));
  const double expected[6] = {2, -1, 0, 0.5, 1, 3};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(j[k], expected[k], 1e-9) << k;
  // An evaluation that fails fails the Jacobian.
  EXPECT_FALSE(CentralDifferences([](const double*, double*) { return false; }, x, {1e-3, 1e-3}, 3, j));
}

}  // namespace
}  // namespace twinsim
