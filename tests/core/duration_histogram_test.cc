#include "core/duration_histogram.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace twinsim {
namespace {

TEST(DurationHistogram, BinsAndOverflowAddUpToTheCount) {
  DurationHistogram h(1e-3, 10);  // 1 ms bins to 10 ms
  for (double t : {0.0, 0.4e-3, 1.0e-3, 1.5e-3, 9.99e-3, 10e-3, 25e-3, -1e-3}) h.Add(t);
  long long in_bins = 0;
  for (int b = 0; b < h.bins(); ++b) in_bins += h.count(b);
  EXPECT_EQ(h.count(), 8);
  EXPECT_EQ(h.overflow(), 2);  // 10 ms and 25 ms
  EXPECT_EQ(in_bins + h.overflow(), h.count());
  EXPECT_EQ(h.count(0), 3);    // 0, 0.4 ms and the negative one, counted as 0
  EXPECT_EQ(h.count(1), 2);
  EXPECT_EQ(h.count(9), 1);
  EXPECT_DOUBLE_EQ(h.max(), 25e-3);
  EXPECT_NEAR(h.mean(), (0.4 + 1.0 + 1.5 + 9.99 + 10 + 25) * 1e-3 / 8, 1e-15);
  EXPECT_EQ(h.CountBetween(0, 2e-3), 5);
  EXPECT_EQ(h.CountBetween(2e-3, 1), 3);   // to beyond the last bin takes in the overflow
  EXPECT_EQ(h.CountBetween(0, 1), h.count());
}

TEST(DurationHistogram, QuantilesAreTheUpperEdgeOfTheirBinAndNeverAboveTheMax) {
  DurationHistogram h(1e-6, 100);  // 1 µs bins
  EXPECT_EQ(h.Quantile(0.5), 0);   // empty
  for (int i = 0; i < 100; ++i) h.Add((i + 0.5) * 1e-6);  // one in each bin
  EXPECT_NEAR(h.Quantile(0.5), 50e-6, 1e-12);
  EXPECT_NEAR(h.Quantile(0.99), 99e-6, 1e-12);
  EXPECT_NEAR(h.Quantile(1), 99.5e-6, 1e-12);  // the max, inside the top bin
  h.Add(1);                                     // overflow
  EXPECT_EQ(h.Quantile(1), 1);
}

TEST(DurationHistogram, RejectsEmptyBins) {
  EXPECT_THROW(DurationHistogram(0, 10), std::invalid_argument);
  EXPECT_THROW(DurationHistogram(1e-3, 0), std::invalid_argument);
}

TEST(DurationHistogram, FormatsDurationsInTheUnitThatReadsBest) {
  EXPECT_EQ(FormatDuration(0.91e-3), "910 µs");
  EXPECT_EQ(FormatDuration(16.7e-3), "16.7 ms");
  EXPECT_EQ(FormatDuration(1.25), "1.25 s");
}

}  // namespace
}  // namespace twinsim
