#include "analysis/omni_replay.h"

#include <gtest/gtest.h>

#include <cmath>

#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A log recorded from the analytic model itself (the callers turn camera noise off).
OmniLog RecordReplayLog(const OmniModel& model, double seconds) {
  return testing::RecordLog(model, testing::RandomDrive(1.5, 0, 0), seconds, 21);
}

// Replays through the analytic backend a log recorded from the same model, no noise.
class OmniReplayTest : public ::testing::Test {
 protected:
  OmniReplayTest() {
    model.vision_noise_xy = model.vision_noise_theta = 0;
    options.backend = "analytic";
    options.state = OmniReplayState::kTracker;
  }
  OmniModel model = testing::Omni4();
  OmniReplayOptions options;
};

TEST_F(OmniReplayTest, SameModelPredictsItsOwnLogFourFramesAhead) {
  const OmniLog log = RecordReplayLog(model, 20);
  const OmniReplayResult r = ReplayOmniLog(model, log, options);
  // The tracker starts at frame D and predicts after its warm-up: rows before
  // D + kWarmUpFrames + K hold the measurement, all others are predicted.
  const int first = 4 + kWarmUpFrames + 4;
  EXPECT_EQ(r.num_predicted(), static_cast<int>(log.rows.size()) - first);
  EXPECT_FALSE(r.predicted[first - 1]);
  EXPECT_TRUE(r.predicted[first]);
  // The tracker is the recording model itself, corrected to poses it would have had
  // anyway: the predictions are the log, to rounding of the CSV, but for the frames at
  // rest where the noise-free camera repeats its pose (no new measurement, CONTRACT.md):
  // there the tracker runs on its own state.
  EXPECT_LT(PositionRmse(log, r), 2e-5);
}

// The observer on the model's own noise-free log: it starts at the first row (the
// tracker at frame D), and its estimate, which weighs the camera against the model,
// predicts the log to a fraction of a millimetre.
TEST_F(OmniReplayTest, TheObserverPredictsTheSameModelsLogFromItsFirstRow) {
  const OmniLog log = RecordReplayLog(model, 20);
  options.state = OmniReplayState::kObserver;
  const OmniReplayResult r = ReplayOmniLog(model, log, options);
  EXPECT_EQ(r.state, "observer");
  const int first = kWarmUpFrames + 4;
  EXPECT_EQ(r.num_predicted(), static_cast<int>(log.rows.size()) - first);
  EXPECT_FALSE(r.predicted[first - 1]);
  EXPECT_TRUE(r.predicted[first]);
  EXPECT_LT(PositionRmse(log, r), 5e-4);
}

TEST_F(OmniReplayTest, TheRightDelayPredictsBetterThanNone) {
  const OmniLog log = RecordReplayLog(model, 20);
  OmniModel no_delay = model;
  no_delay.command_delay_frames = no_delay.vision_delay_frames = 0;
  const double right = PositionRmse(log, ReplayOmniLog(model, log, options));
  const double wrong = PositionRmse(log, ReplayOmniLog(no_delay, log, options));
  EXPECT_LT(3 * right, wrong) << "delay 4: " << right << " m, delay 0: " << wrong << " m";
}

TEST_F(OmniReplayTest, FreeRunFromTheFirstRowFollowsTheSameModel) {
  const OmniLog log = RecordReplayLog(model, 10);
  options.horizon = 0;
  const OmniReplayResult r = ReplayOmniLog(model, log, options);
  EXPECT_EQ(r.num_predicted(), static_cast<int>(log.rows.size()) - 1);
  EXPECT_LT(PositionRmse(log, r), 0.01);
}

}  // namespace
}  // namespace twinsim
