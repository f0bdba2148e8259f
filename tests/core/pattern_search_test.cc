// The compass search of core/pattern_search.h: it finds a smooth bowl's minimum to its
// last step, keeps within its clamp and budget, and computes no point's cost twice.
#include "core/pattern_search.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>

namespace twinsim {
namespace {

using Point = std::array<double, 2>;

// A bowl in the coordinates (logarithms of two factors) with its floor at (0.3, -0.2),
// counting the calls per point.
struct Bowl {
  std::map<Point, int> calls;
  double operator()(const Point& p) {
    ++calls[p];
    return std::pow(p[0] - 0.3, 2) + 2 * std::pow(p[1] + 0.2, 2) + 0.5 * (p[0] - 0.3) * (p[1] + 0.2);
  }
};

TEST(PatternSearch, FindsABowlsFloorToItsLastStepAndComputesNoPointTwice) {
  Bowl bowl;
  const std::function<double(const Point&)> cost = [&](const Point& p) { return bowl(p); };
  const std::function<Point(Point)> clamp = [](Point p) { return p; };
  const Point start{0, 0};
  double best = cost(start);
  int evaluations = 1;
  const Point found = PatternSearch<Point>(cost, clamp, start, 2, 500, &best, &evaluations);
  // The last step is ln(1.05) / 2 or so: within it of the floor on each coordinate.
  EXPECT_NEAR(found[0], 0.3, std::log(1.05));
  EXPECT_NEAR(found[1], -0.2, std::log(1.05));
  EXPECT_EQ(best, cost(found));
  EXPECT_LT(evaluations, 500);
  // Polls back to the point a move came from are counted, not computed again.
  int computed = 0;
  for (const auto& [point, n] : bowl.calls) {
    EXPECT_LE(n, 2) << point[0] << ", " << point[1];  // the search's once, and the check's for `found`
    computed += n;
  }
  EXPECT_LT(computed - 1, evaluations) << "every counted evaluation was computed";
}

TEST(PatternSearch, StaysWithinItsClampAndItsBudget) {
  const std::function<double(const Point&)> cost = [](const Point& p) { return std::pow(p[0] - 5, 2) + p[1] * p[1]; };
  const std::function<Point(Point)> clamp = [](Point p) {
    p[0] = std::min(p[0], 1.0);
    return p;
  };
  double best = cost({0, 0});
  int evaluations = 1;
  const Point found = PatternSearch<Point>(cost, clamp, {0, 0}, 2, 500, &best, &evaluations);
  EXPECT_EQ(found[0], 1.0);  // the bound, where the cost is least within it
  best = cost({0, 0});
  evaluations = 1;
  PatternSearch<Point>(cost, clamp, {0, 0}, 2, 7, &best, &evaluations);
  EXPECT_EQ(evaluations, 7);
}

// With a min_gain, a move must lower the cost by more than it: along a gentle slope
// (0.01 per unit, 0.007 a step of ln 2) the search stays where every gain is smaller,
// and walks on where the gain allows; on the bowl it still reaches the floor, within
// the precision the gain leaves it.
TEST(PatternSearch, AMinGainStopsMovesThatGainLess) {
  const std::function<Point(Point)> clamp = [](Point p) {
    p[0] = std::max(p[0], -10.0);
    return p;
  };
  const std::function<double(const Point&)> slope = [](const Point& p) { return 0.01 * p[0] + p[1] * p[1]; };
  double best = slope({0, 0});
  int evaluations = 1;
  Point found = PatternSearch<Point>(slope, clamp, {0, 0}, 2, 500, &best, &evaluations, 0.01);
  EXPECT_EQ(found[0], 0.0);  // every step (ln 2 at most) gains 0.0069 or less: below 0.01
  best = slope({0, 0});
  evaluations = 1;
  found = PatternSearch<Point>(slope, clamp, {0, 0}, 2, 500, &best, &evaluations, 0.005);
  EXPECT_LT(found[0], -1.0);  // each step of ln 2 gains 0.0069: it walks
  best = slope({0, 0});
  evaluations = 1;
  found = PatternSearch<Point>(slope, clamp, {0, 0}, 2, 500, &best, &evaluations);
  EXPECT_EQ(found[0], -10.0);  // every gain: down to the clamp

  Bowl bowl;
  const std::function<double(const Point&)> cost = [&](const Point& p) { return bowl(p); };
  const std::function<Point(Point)> none = [](Point p) { return p; };
  best = cost({0, 0});
  evaluations = 1;
  const Point floor = PatternSearch<Point>(cost, none, {0, 0}, 2, 500, &best, &evaluations, 1e-3);
  EXPECT_NEAR(floor[0], 0.3, 0.1);
  EXPECT_NEAR(floor[1], -0.2, 0.1);
}

}  // namespace
}  // namespace twinsim
