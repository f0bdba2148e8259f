#include "core/delay_line.h"

#include <gtest/gtest.h>

namespace twinsim {
namespace {

TEST(DelayLine, HandsValuesOutLengthPushesLate) {
  DelayLine<int> d(3, -1);
  EXPECT_EQ(d.Push(10), -1);
  EXPECT_EQ(d.Push(11), -1);
  EXPECT_EQ(d.Push(12), -1);
  EXPECT_EQ(d.Push(13), 10);
  EXPECT_EQ(d.Front(), 11);
  EXPECT_EQ(d.Push(14), 11);
  EXPECT_EQ(d.InFlight(), (std::vector<int>{12, 13, 14}));
}

TEST(DelayLine, ZeroLengthPassesThrough) {
  DelayLine<int> d(0, -1);
  EXPECT_EQ(d.Push(7), 7);
}

TEST(DelayLine, CopyReplaysExactly) {
  DelayLine<int> a(2, 0);
  a.Push(1);
  DelayLine<int> b = a;
  EXPECT_EQ(a.Push(2), b.Push(2));
  EXPECT_EQ(a.Push(3), b.Push(3));
}

}  // namespace
}  // namespace twinsim
