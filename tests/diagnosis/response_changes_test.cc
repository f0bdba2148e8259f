// Changes of a robot's response part way through a log (diagnosis/response_changes.h):
// the scale's change points on series of known changes and of none, then a robot made in
// twinsim whose floor turns slippery part way.
#include "diagnosis/response_changes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "diagnosis/diagnosis_plants.h"
#include "test_util.h"

namespace twinsim {
namespace {

// y = s(t) x + AR(1) noise (correlated over ~0.3 s at 30 rows a second), x a speed that
// wanders between 0.5 and 1.5; s changes to each of `scales` at each of `at`.
struct Series {
  std::vector<double> t, x, y;
};
Series MakeSeries(double seconds, const std::vector<double>& at, const std::vector<double>& scales, double noise,
                  std::uint64_t seed) {
  Rng rng(seed);
  Series s;
  double e = 0;
  const double phi = std::exp(-1.0 / 9);  // 0.3 s at 30 rows/s
  for (int i = 0; i < static_cast<int>(seconds * 30); ++i) {
    const double t = i / 30.0;
    double scale = 1.0;
    for (std::size_t k = 0; k < at.size(); ++k)
      if (t >= at[k]) scale = scales[k];
    e = phi * e + std::sqrt(1 - phi * phi) * rng.Gaussian(noise);
    const double x = 1.0 + 0.5 * std::sin(0.7 * t);
    s.t.push_back(t);
    s.x.push_back(x);
    s.y.push_back(scale * x + e);
  }
  return s;
}

TEST(ScaleChanges, FindsAFallInScaleWhereItHappens) {
  const Series s = MakeSeries(12, {4.2}, {0.5}, 0.05, 1);
  const std::vector<ScaleChange> c = FindScaleChanges(s.t, s.x, s.y);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NEAR(c[0].t, 4.2, 0.3);
  EXPECT_NEAR(c[0].before, 1.0, 0.05);
  EXPECT_NEAR(c[0].after, 0.5, 0.05);
  EXPECT_GT(c[0].t_stat, 5);
}

TEST(ScaleChanges, FindsTwoChangesInTimeOrder) {
  // A floor that turns slippery and back (the Robotino's runs across two floors do so).
  const Series s = MakeSeries(15, {4, 9}, {0.5, 1.0}, 0.1, 2);
  const std::vector<ScaleChange> c = FindScaleChanges(s.t, s.x, s.y);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_NEAR(c[0].t, 4, 0.3);
  EXPECT_NEAR(c[1].t, 9, 0.3);
  EXPECT_NEAR(c[0].before, 1.0, 0.1);
  EXPECT_NEAR(c[0].after, 0.5, 0.1);
  EXPECT_EQ(c[1].before, c[0].after);  // one piece between them, one scale
  EXPECT_NEAR(c[1].after, 1.0, 0.1);
}

TEST(ScaleChanges, KeepsItsLevelOnCorrelatedNoiseWithoutAChange) {
  // The largest of hundreds of split points, on rows correlated over 0.3 s: a plain
  // t > 2 would speak on most series. Noise 4x the one above, so that a 10 % wander
  // could pass the size rule if the test let it.
  int flagged = 0;
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    const Series s = MakeSeries(12, {}, {}, 0.4, seed);
    flagged += !FindScaleChanges(s.t, s.x, s.y).empty();
  }
  EXPECT_LE(flagged, 2) << "of 100 series without a change";
}

TEST(ScaleChanges, ASmallChangeIsNotAChange) {
  // 8 % is under the 15 % a change must reach, however clear it is.
  const Series s = MakeSeries(12, {6}, {0.92}, 0.01, 3);
  EXPECT_TRUE(FindScaleChanges(s.t, s.x, s.y).empty());
  ScaleChangeOptions finer;
  finer.min_relative = 0.05;
  ASSERT_EQ(FindScaleChanges(s.t, s.x, s.y, finer).size(), 1u);
}

TEST(ScaleChanges, EachSideSpansTheShortestSegment) {
  // A change 0.5 s before the end is not resolved: too few rows to tell a floor from a bump.
  const Series s = MakeSeries(10, {9.5}, {0.3}, 0.05, 4);
  EXPECT_TRUE(FindScaleChanges(s.t, s.x, s.y).empty());
}

TEST(OmniResponseChanges, AFloorThatTurnsSlipperyPartWay) {
  // The plant drives at 0.7 of its commands from t = 6 s on (a velocity_scale appears);
  // the model is the plant before the change.
  OmniModel before = testing::Omni4();
  OmniModel after = before;
  after.effects.axis_scale = {0.7, 0.7, 1.0};
  const OmniLog first = testing::RecordOmniPlant(before, 6, 11);
  const OmniLog second = testing::RecordOmniPlant(after, 6, 12);
  OmniLog log = first;
  const double shift = first.rows.back().t + first.frame_period;
  for (OmniLogRow row : second.rows) {
    row.t += shift;
    log.rows.push_back(row);
    log.line_of.push_back(static_cast<int>(log.rows.size()) + 1);
  }
  log.path = "floor_change.csv";
  const std::vector<ResponseChange> changes = FindOmniResponseChanges(before, {log}, "analytic");
  ASSERT_GE(changes.size(), 1u);
  EXPECT_EQ(changes[0].log, "floor_change.csv");
  EXPECT_EQ(changes[0].quantity, "velocity scale");
  EXPECT_NEAR(changes[0].t, shift, 1.0);
  EXPECT_NEAR(changes[0].after / changes[0].before, 0.7, 0.1);
  EXPECT_NE(changes[0].what.find("the velocity scale fell from"), std::string::npos) << changes[0].what;
  // The same plant throughout: nothing.
  EXPECT_TRUE(FindOmniResponseChanges(before, {testing::RecordOmniPlant(before, 12, 13)}, "analytic").empty());
}

}  // namespace
}  // namespace twinsim
