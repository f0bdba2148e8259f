#include "tuning/policy_gradient.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/parallel.h"

namespace twinsim {
namespace {

TEST(PolicyGradient, StepRuleOfEquation6) {
  EXPECT_EQ(PolicyGradientStep(1.0, 2.0, 0.5), 0);   // the unperturbed group is best: stay
  EXPECT_EQ(PolicyGradientStep(3.0, 2.0, 0.5), 1);   // + beats -
  EXPECT_EQ(PolicyGradientStep(1.0, 2.0, 2.5), -1);  // - beats +
  EXPECT_EQ(PolicyGradientStep(3.0, 2.0, 3.0), 0);   // a tie does not move
  EXPECT_EQ(PolicyGradientStep(3.0, NAN, 1.0), 1);   // no unperturbed set: + against -
  EXPECT_EQ(PolicyGradientStep(NAN, 1.0, 2.0), -1);  // one side only: against the middle
  EXPECT_EQ(PolicyGradientStep(NAN, 1.0, 0.5), 0);
}

TEST(PolicyGradient, PowerMeanOfEquation5) {
  const std::vector<double> all = {-3, -1, 0, 2, 5};
  // Exponent 1 is the plain mean, shift or no shift.
  EXPECT_NEAR(PowerMeanQuality({-1, 2}, all, 1), 0.5, 1e-9);
  // A larger exponent moves the average towards the group's best.
  const double m2 = PowerMeanQuality({-1, 2}, all, 2), m8 = PowerMeanQuality({-1, 2}, all, 8);
  EXPECT_GT(m2, 0.5);
  EXPECT_GT(m8, m2);
  EXPECT_LT(m8, 2.0 + 1e-9);
  EXPECT_TRUE(std::isnan(PowerMeanQuality({}, all, 1)));
}

// On a smooth quality with a known best point the search walks there and stays within
// one step of it: the parameters' steps of +-eta reach p* = (3, -2, 0.5) exactly
// because p* lies on the step grid from the start.
TEST(PolicyGradient, FindsTheBestPointOfAQuadratic) {
  const Eigen::Vector3d best(3.0, -2.0, 0.5);
  auto evaluate = [&](const std::vector<Eigen::VectorXd>& sets) {
    std::vector<double> q;
    for (const auto& p : sets) q.push_back(-(p - best).squaredNorm());
    return q;
  };
  PolicyGradientOptions o;
  o.sets_per_iteration = 20;
  o.max_iterations = 60;
  o.epsilon = Eigen::Vector3d(0.5, 0.5, 0.1);
  o.eta = Eigen::Vector3d(0.5, 0.5, 0.1);
  o.seed = 7;
  const PolicyGradientSummary s = PolicyGradientSearch(Eigen::Vector3d::Zero(), o, evaluate);
  EXPECT_LT((s.best_parameters - best).cwiseAbs().maxCoeff(), 1e-9) << s.FullReport();
  EXPECT_NEAR(s.best_quality, 0.0, 1e-12);
  EXPECT_EQ(s.evaluations, static_cast<int>(s.iterations.size()) * 21);
  // The same seed gives the same search.
  const PolicyGradientSummary again = PolicyGradientSearch(Eigen::Vector3d::Zero(), o, evaluate);
  ASSERT_EQ(again.iterations.size(), s.iterations.size());
  for (std::size_t i = 0; i < s.iterations.size(); ++i)
    EXPECT_EQ(again.iterations[i].qualities, s.iterations[i].qualities);
}

TEST(PolicyGradient, KeepsWithinBoundsAndStopsWithoutProgress) {
  auto evaluate = [](const std::vector<Eigen::VectorXd>& sets) {
    std::vector<double> q;
    for (const auto& p : sets) q.push_back(p.sum());  // better the larger: runs into the bound
    return q;
  };
  PolicyGradientOptions o;
  o.max_iterations = 50;
  o.epsilon = o.eta = Eigen::Vector2d(1, 1);
  o.lower = Eigen::Vector2d(0, 0);
  o.upper = Eigen::Vector2d(4, 2);
  o.patience = 3;
  const PolicyGradientSummary s = PolicyGradientSearch(Eigen::Vector2d::Zero(), o, evaluate);
  for (const auto& it : s.iterations)
    for (const auto& set : it.sets) EXPECT_TRUE((set.array() >= 0).all() && set[0] <= 4 && set[1] <= 2);
  EXPECT_DOUBLE_EQ(s.best_quality, 6.0);
  EXPECT_LT(s.iterations.size(), 50u);  // stopped: the best set cannot improve
}

TEST(PolicyGradient, RejectsInvalidOptions) {
  PolicyGradientOptions o;
  o.epsilon = Eigen::Vector2d(1, 1);
  o.eta = Eigen::Vector3d(1, 1, 1);
  std::string why;
  EXPECT_FALSE(o.IsValid(2, &why));
  EXPECT_NE(why.find("eta"), std::string::npos);
  EXPECT_THROW(PolicyGradientSearch(Eigen::Vector2d::Zero(), o, {}), InputError);
}

TEST(Parallel, ResultsDoNotDependOnTheThreadCount) {
  auto run = [](int threads) {
    std::vector<double> out(101);
    ParallelFor(101, threads, [&](int i) { out[i] = std::sin(i) * i; });
    return out;
  };
  EXPECT_EQ(run(1), run(2));
  EXPECT_EQ(run(1), run(7));
  EXPECT_THROW(ParallelFor(10, 2, [](int i) { if (i == 5) throw std::runtime_error("five"); }), std::runtime_error);
}

}  // namespace
}  // namespace twinsim
