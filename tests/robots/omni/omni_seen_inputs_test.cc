// The inputs a fit saw (robots/omni/omni_seen_inputs.h): wheel speeds of the command and
// the body, a farthest-point subsample that covers every fit frame, distances in units of
// the seen commands' size.
#include "robots/omni/omni_seen_inputs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/math_constants.h"
#include "robots/omni/omni_kinematics.h"
#include "test_util.h"

namespace twinsim {
namespace {

// The input is the kinematics' wheel speeds of the command, then of the body's velocity.
TEST(OmniSeenInputs, AFramesInputIsTheWheelSpeedsAskedAndReached) {
  const OmniModel m = testing::Omni4();
  const OmniKinematics kin(m);
  const Twist2 command{0.8, -0.3, 2.0}, velocity{0.5, 0.1, -1.0};
  const Eigen::VectorXd u = SeenInputFeature(kin.wheels_from_body(), command, velocity);
  ASSERT_EQ(u.size(), 2 * m.num_wheels());
  EXPECT_LT((u.head(m.num_wheels()) - kin.WheelSpeeds(command)).norm(), 1e-12);
  EXPECT_LT((u.tail(m.num_wheels()) - kin.WheelSpeeds(velocity)).norm(), 1e-12);
}

// Inputs on a circle of commands (and a body at rest): every one within the covering
// distance of a kept point, a kept point at distance 0, the scale their RMS size, and an
// input twice as far out as the circle at the distance its gap says.
TEST(OmniSeenInputs, TheSubsampleCoversEveryInputAndMeasuresInCommandSizes) {
  std::vector<Eigen::VectorXd> inputs;
  for (int i = 0; i < 2000; ++i) {
    const double a = 2 * kPi * i / 2000.0;
    Eigen::VectorXd u = Eigen::VectorXd::Zero(4);
    u << 3 * std::cos(a), 3 * std::sin(a), 0, 0;
    inputs.push_back(u);
  }
  const OmniSeenInputs seen = MakeSeenInputs(inputs, 64);
  EXPECT_EQ(seen.points.size(), 64u);
  EXPECT_NEAR(seen.scale, 3.0, 1e-12);
  // 64 points on a circle of radius 3 (circumference 18.8) leave gaps of about 0.3:
  // every input within half a gap, 0.05 of the scale.
  EXPECT_LT(seen.covering, 0.06);
  EXPECT_GT(seen.covering, 0.0);
  for (const Eigen::VectorXd& u : inputs) EXPECT_LE(seen.Distance(u), seen.covering + 1e-12);
  EXPECT_EQ(seen.Distance(seen.points[10]), 0.0);
  Eigen::VectorXd far = Eigen::VectorXd::Zero(4);
  far << 6, 0, 0, 0;
  EXPECT_NEAR(seen.Distance(far), 1.0, 1e-9);  // 3 rad/s out, over a scale of 3
  // The same inputs, the same subsample; fewer inputs than points, each kept once.
  const OmniSeenInputs again = MakeSeenInputs(inputs, 64);
  for (std::size_t i = 0; i < seen.points.size(); ++i) EXPECT_EQ(seen.points[i], again.points[i]);
  const OmniSeenInputs few = MakeSeenInputs({inputs[0], inputs[500], inputs[0]}, 64);
  EXPECT_EQ(few.points.size(), 2u);
  EXPECT_EQ(few.covering, 0.0);
  EXPECT_TRUE(MakeSeenInputs({}).empty());
  EXPECT_EQ(MakeSeenInputs({}).Distance(far), 0.0);
}

}  // namespace
}  // namespace twinsim
