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

// With `reach`, the observer predicts only from the frames it names and its filter stops
// at the last of them; every prediction it makes is the full replay's, to the bit, pose
// and covariance (the noise fit's evaluations rely on it: docs/identification.md).
TEST_F(OmniReplayTest, TheObserverWithAReachPredictsWhatTheFullReplayDoes) {
  OmniModel noisy = testing::Omni4();  // the camera's noise on: the filter's gain matters
  const OmniLog log = RecordReplayLog(noisy, 12);
  options.state = OmniReplayState::kObserver;
  options.horizon = 16;
  options.also = {4};
  options.covariance = true;
  const OmniReplayResult full = ReplayOmniLog(noisy, log, options);
  const int first = 200, last = 260;  // frames a prediction starts from, 4 or 16 ahead
  options.reach = [&](int frame) { return frame >= first && frame < last ? (frame % 2 ? 4 : 16) : 0; };
  std::vector<int> reported;  // the frames the replay's progress names: the filter's
  const OmniReplayResult part =
      ReplayOmniLog(noisy, log, options, [&](int frame, int) { reported.push_back(frame); });
  // The filter stopped at the last frame `reach` names (progress every 64th frame, then
  // the log's last): nothing between.
  const int last_frame = log.FrameIndex(log.rows.size() - 1);
  ASSERT_GT(last_frame, last + 64);
  for (int frame : reported) EXPECT_TRUE(frame < last || frame == last_frame) << frame;
  int compared = 0;
  for (std::size_t row = 0; row < log.rows.size(); ++row) {
    const int frame = log.FrameIndex(row);
    const bool in_reach = frame >= first + 4 && frame < last + 16;
    EXPECT_TRUE(!part.predicted[row] || in_reach) << row;
    EXPECT_TRUE(!part.also[0].predicted[row] || (frame >= first + 4 && frame < last + 4)) << row;
    // Every start within the reach predicts, the last one too.
    const int from16 = frame - 16, from4 = frame - 4;
    if (from16 >= first && from16 < last && from16 % 2 == 0) {
      EXPECT_TRUE(part.predicted[row]) << row;
    }
    if (from4 >= first && from4 < last) {
      EXPECT_TRUE(part.also[0].predicted[row]) << row;
    }
    for (int h = 0; h < 2; ++h) {
      const OmniReplayResult& a = h == 0 ? part : part.also[0];
      const OmniReplayResult& b = h == 0 ? full : full.also[0];
      if (!a.predicted[row]) continue;
      ASSERT_TRUE(b.predicted[row]) << row;
      EXPECT_EQ(a.pose[row].x, b.pose[row].x) << row;
      EXPECT_EQ(a.pose[row].y, b.pose[row].y) << row;
      EXPECT_EQ(a.pose[row].theta, b.pose[row].theta) << row;
      EXPECT_EQ(a.covariance[row], b.covariance[row]) << row;
      ++compared;
    }
  }
  EXPECT_GT(compared, 80);  // 30 rows 16 frames ahead, 60 at 4
}

}  // namespace
}  // namespace twinsim
