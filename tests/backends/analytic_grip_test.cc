// The analytic omni model cannot slip; it says where it would have to: the steps on which
// a wheel needed more grip than wheel_friction times its load. Checked against ODE, which
// slips: where the analytic model stays within its grip the two agree, where it does not
// they part (issue 41: a clean log recorded by ODE and diagnosed on the analytic model
// disagreed in fast turns).
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/omni_replay.h"
#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "backends/engine_drives.h"
#include "test_util.h"

namespace twinsim {
namespace {

OmniModel QuietOmni4() { return testing::Quiet(testing::Omni4()); }

// A constant robot-frame command to drive at `speed` while turning at `omega`: the
// velocity turns with the robot, a centripetal acceleration of speed x omega.
CommandSpec Circle(double speed, double omega) {
  CommandSpec spec;
  spec.type = "sequence";
  spec.segments = {{3.0, Twist2{speed, 0, omega}, false}};
  return spec;
}

TEST(AnalyticGrip, WithinItsGripTheAnalyticModelSaysSoAndAgreesWithOde) {
  if (AvailableOmniEngines().size() < 2) GTEST_SKIP() << "needs ODE";
  // The shipped 2 m/s^2 ramps (docs/backends.md): the 45 degree test drive and a gentle
  // circle (1 m/s at 1.5 rad/s: 1.5 m/s^2 inward).
  for (const CommandSpec& spec : {testing::TestDrive45(), Circle(1.0, 1.5)}) {
    const SimulationResult analytic = testing::Drive("analytic", QuietOmni4(), spec, 3.0);
    const SimulationResult ode = testing::Drive("ode", QuietOmni4(), spec, 3.0);
    EXPECT_EQ(analytic.grip.steps, 91 * DefaultPhysicsSubsteps(30));  // every physics step of the 91 frames
    EXPECT_EQ(analytic.grip.beyond, 0) << spec.type << ": worst " << analytic.grip.worst;
    EXPECT_LT(analytic.grip.worst, 1.0);
    EXPECT_GT(analytic.grip.worst, 0.05);  // it is checked, and the drive asks for grip
    EXPECT_EQ(ode.grip.steps, 0);          // ODE slips: it does not check
    EXPECT_TRUE(DescribeGrip(analytic.grip).empty());
    const auto [position, heading] = testing::LargestTruthDifference(analytic, ode);
    EXPECT_LT(position, 0.02) << spec.type;
    EXPECT_LT(heading, 1.0 * kPi / 180) << spec.type;
  }
}

TEST(AnalyticGrip, BeyondItsGripTheAnalyticModelSaysSoAndOdeSlipsAway) {
  if (AvailableOmniEngines().size() < 2) GTEST_SKIP() << "needs ODE";
  // 3 m/s^2 ramps: the 45 degree drive's hard stop needs more than the two diagonal
  // wheels transmit (docs/backends.md: both engines yaw); and the fast turn of issue 41
  // (1.9 m/s at 3.8 rad/s: 7.2 m/s^2 inward, above wheel_friction x g).
  OmniModel steep = QuietOmni4();
  steep.controller.forward.slew_rate = steep.controller.sideways.slew_rate = 3;
  struct Case {
    const char* label;
    OmniModel model;
    CommandSpec spec;
  };
  for (const Case& c : {Case{"3 m/s^2 ramps", steep, testing::TestDrive45()}, Case{"fast turn", QuietOmni4(), Circle(1.9, 3.8)}}) {
    const SimulationResult analytic = testing::Drive("analytic", c.model, c.spec, 3.0);
    const SimulationResult ode = testing::Drive("ode", c.model, c.spec, 3.0);
    EXPECT_GT(analytic.grip.beyond, 0) << c.label;
    EXPECT_GT(analytic.grip.worst, 1.0) << c.label;
    const std::string text = DescribeGrip(analytic.grip);
    EXPECT_NE(text.find("slips there and the analytic model cannot"), std::string::npos) << text;
    const auto [position, heading] = testing::LargestTruthDifference(analytic, ode);
    EXPECT_GT(std::max(position / 0.02, heading / (1.0 * kPi / 180)), 1.0)
        << c.label << ": the engines agree where the analytic model says they should part (" << position << " m, "
        << heading << " rad)";
  }
}

// A pass of the grip is said where it could move the robot: some step at 5 % over it, or
// 1 % of the steps over it at all; not a handful of steps a hair over it.
TEST(AnalyticGrip, AHairOverTheGripOnAFewStepsIsNotSaid) {
  GripCheck grip;
  grip.steps = 531300;  // a replay of a minute with predictions 16 frames ahead
  grip.beyond = 5;
  grip.worst = 1.0025;
  EXPECT_TRUE(DescribeGrip(grip).empty());
  grip.worst = 1.06;
  EXPECT_NE(DescribeGrip(grip).find("up to 1.1 times it"), std::string::npos) << DescribeGrip(grip);
  grip.worst = 1.01;
  grip.beyond = grip.steps / 100;
  EXPECT_NE(DescribeGrip(grip).find("on 1 % of the steps"), std::string::npos) << DescribeGrip(grip);
  grip.beyond = grip.steps / 100 - 1;
  EXPECT_TRUE(DescribeGrip(grip).empty());
}

// Replaying a log (replay, compare, diagnose and identify all do) carries the check out:
// a fast turn recorded by ODE is flagged on the analytic model, a gentle one is not.
TEST(AnalyticGrip, AReplayOfALogSaysWhereTheAnalyticModelLeftItsGrip) {
  if (AvailableOmniEngines().size() < 2) GTEST_SKIP() << "needs ODE";
  const OmniModel model = testing::Omni4();
  OmniReplayOptions options;
  options.backend = "analytic";
  const OmniReplayResult fast = ReplayOmniLog(model, testing::RecordLog(model, Circle(1.9, 3.8), 3.0, 1, "ode"), options);
  EXPECT_GT(fast.grip.beyond, fast.grip.steps / 4);
  EXPECT_NE(DescribeGrip(fast.grip).find("where it slipped, they simulate the slip"), std::string::npos);
  const OmniReplayResult gentle = ReplayOmniLog(model, testing::RecordLog(model, Circle(1.0, 1.5), 3.0, 1, "ode"), options);
  EXPECT_GT(gentle.grip.steps, 0);
  EXPECT_EQ(gentle.grip.beyond, 0) << gentle.grip.worst;
  options.backend = "ode";  // it slips: nothing to check
  EXPECT_EQ(ReplayOmniLog(model, testing::RecordLog(model, Circle(1.9, 3.8), 3.0, 1, "ode"), options).grip.steps, 0);
}

}  // namespace
}  // namespace twinsim
