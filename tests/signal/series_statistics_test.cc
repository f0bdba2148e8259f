// The one lag estimator (signal/series_statistics.h, BestAlignment) and the correlation
// it rests on.
#include "signal/series_statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace twinsim {
namespace {

// A chirp-like series no shift of which resembles another.
std::vector<double> Series(int n, int offset) {
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double t = (i + offset) * 0.01;
    x[static_cast<std::size_t>(i)] = std::sin(3 * t + 2 * t * t) + 0.3 * std::cos(17 * t);
  }
  return x;
}

// b[i + 7] = a[i]: the shift is 7, whichever way the scan runs, with correlation 1;
// an inverted copy is found only by magnitude, its correlation -1.
TEST(SeriesStatistics, BestAlignmentFindsAKnownShiftScannedEitherWay) {
  const std::vector<double> a = Series(400, 0), b = Series(400, -7);
  const Alignment up = BestAlignment(a, b, -20, 20);
  EXPECT_EQ(up.shift, 7);
  EXPECT_NEAR(up.correlation, 1.0, 1e-12);
  EXPECT_EQ(BestAlignment(a, b, 20, -20).shift, 7);
  EXPECT_EQ(BestAlignment(b, a, -20, 20).shift, -7);
  std::vector<double> inverted = b;
  for (double& v : inverted) v = -v;
  const Alignment by_magnitude = BestAlignment(a, inverted, 20, -20, true);
  EXPECT_EQ(by_magnitude.shift, 7);
  EXPECT_NEAR(by_magnitude.correlation, -1.0, 1e-12);
  EXPECT_NE(BestAlignment(a, inverted, -20, 20).shift, 7);  // signed: an inverted copy is the worst match
}

// Ties: a constant series correlates 0 at every shift. Signed, the first shift scanned
// is kept; by magnitude nothing beats 0 and the shift is 0. Shifts beyond the overlap
// leave too few pairs and correlate 0.
TEST(SeriesStatistics, BestAlignmentKeepsTheFirstTieAndZeroByMagnitude) {
  const std::vector<double> flat(50, 1.0), a = Series(50, 0);
  EXPECT_EQ(BestAlignment(flat, a, 3, 9).shift, 3);
  EXPECT_EQ(BestAlignment(flat, a, 9, 3).shift, 9);
  const Alignment none = BestAlignment(flat, a, -5, 5, true);
  EXPECT_EQ(none.shift, 0);
  EXPECT_EQ(none.correlation, 0.0);
  EXPECT_EQ(Correlation(a, flat), 0.0);
  EXPECT_EQ(BestAlignment(a, a, 49, 60).correlation, 0.0);  // one pair, then none
  EXPECT_NEAR(Correlation(a, a), 1.0, 1e-12);
}

}  // namespace
}  // namespace twinsim
