#include "analysis/omni_replay.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/simulation.h"
#include "scene/command_source.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A log recorded from the analytic model itself, without camera noise.
OmniLog RecordLog(const OmniModel& model, double seconds) {
  CommandSpec random;
  random.type = "random";
  random.max_speed = 1.5;
  FrameTiming timing;
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{}, MakeCommandSource(random, 21, 0, seconds, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {model}, FieldModel{}, timing), 21);
  SimulationResult r = sim.Run(static_cast<int>(seconds * 30) + 1);
  std::vector<OmniLogRow> rows;
  for (const auto& f : r.frames[0]) rows.push_back({f.t, f.seen, f.command});
  return ParseOmniLog(FormatOmniLog(rows), "recorded.csv");
}

TEST(OmniReplay, SameModelPredictsItsOwnLogFourFramesAhead) {
  OmniModel m = testing::Omni4();
  m.vision_noise_xy = m.vision_noise_theta = 0;
  const OmniLog log = RecordLog(m, 20);
  OmniReplayOptions options;
  options.backend = "analytic";
  const OmniReplayResult r = ReplayOmniLog(m, log, options);
  // Rows 0..K+D-1 lack history; all others are predicted.
  EXPECT_EQ(r.num_predicted(), static_cast<int>(log.rows.size()) - 8);
  EXPECT_FALSE(r.predicted[7]);
  EXPECT_TRUE(r.predicted[8]);
  // Only the start state is estimated (velocity by a backward difference, the
  // controller's integral unknown), so four frames ahead stay within millimetres.
  EXPECT_LT(PositionRmse(log, r), 0.005);
}

TEST(OmniReplay, TheRightDelayPredictsBetterThanNone) {
  OmniModel m = testing::Omni4();
  m.vision_noise_xy = m.vision_noise_theta = 0;
  const OmniLog log = RecordLog(m, 20);
  OmniReplayOptions options;
  options.backend = "analytic";
  OmniModel no_delay = m;
  no_delay.command_delay_frames = no_delay.vision_delay_frames = 0;
  const double right = PositionRmse(log, ReplayOmniLog(m, log, options));
  const double wrong = PositionRmse(log, ReplayOmniLog(no_delay, log, options));
  EXPECT_LT(3 * right, wrong) << "delay 4: " << right << " m, delay 0: " << wrong << " m";
}

TEST(OmniReplay, FreeRunFromTheFirstRowFollowsTheSameModel) {
  OmniModel m = testing::Omni4();
  m.vision_noise_xy = m.vision_noise_theta = 0;
  const OmniLog log = RecordLog(m, 10);
  OmniReplayOptions options;
  options.backend = "analytic";
  options.horizon = 0;
  const OmniReplayResult r = ReplayOmniLog(m, log, options);
  EXPECT_EQ(r.num_predicted(), static_cast<int>(log.rows.size()) - 1);
  EXPECT_LT(PositionRmse(log, r), 0.01);
}

}  // namespace
}  // namespace twinsim
