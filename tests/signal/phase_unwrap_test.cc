#include "signal/phase_unwrap.h"

#include <gtest/gtest.h>

namespace twinsim {
namespace {

TEST(PhaseUnwrap, AddsWholeTurnsWhereThePhaseJumps) {
  const std::vector<double> out = UnwrapDegrees({170, -170, -150, 175, -90});
  const std::vector<double> expected = {170, 190, 210, 175, 270};
  ASSERT_EQ(out.size(), expected.size());
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_NEAR(out[i], expected[i], 1e-12) << i;
}

TEST(PhaseUnwrap, FollowsAFallingPhaseOverManyTurns) {
  // A pure delay: -36 degrees per line, wrapped into (-180, 180].
  std::vector<double> wrapped;
  for (int i = 0; i < 40; ++i) {
    double a = -36.0 * i;
    while (a <= -180) a += 360;
    wrapped.push_back(a);
  }
  const std::vector<double> out = UnwrapDegrees(wrapped);
  for (int i = 0; i < 40; ++i) EXPECT_NEAR(out[static_cast<std::size_t>(i)], -36.0 * i, 1e-9) << i;
}

TEST(PhaseUnwrap, KeepsTheFirstValueAndEmptyInput) {
  EXPECT_TRUE(UnwrapDegrees({}).empty());
  const std::vector<double> one = UnwrapDegrees({-179});
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0], -179);
}

}  // namespace
}  // namespace twinsim
