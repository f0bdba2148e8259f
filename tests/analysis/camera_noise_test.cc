// The camera's noise seen from an omni log alone (analysis/camera_noise.h).
#include "analysis/camera_noise.h"

#include <gtest/gtest.h>

#include <cmath>

#include "diagnosis/diagnosis_plants.h"
#include "test_util.h"

namespace twinsim {
namespace {

// The camera noise estimated on a log with repeated frames and jitter is the camera's.
TEST(OmniNoiseFloor, RightOnLogsWithRepeatedFrames) {
  testing::OmniRecording how;
  how.backend = "analytic";
  how.repeat_share = 0.1;
  how.noise_xy = 0.002;
  how.noise_theta = 0.004;
  const std::vector<OmniLog> logs = {testing::RecordOmniOpenWorld(testing::Omni4(), 20, 3, how)};
  double var_xy = 0, var_theta = 0;
  OmniNoiseFloor(logs, 0.09, &var_xy, &var_theta);
  EXPECT_NEAR(std::sqrt(var_xy), how.noise_xy, 0.25 * how.noise_xy);
  EXPECT_NEAR(std::sqrt(var_theta), how.noise_theta, 0.25 * how.noise_theta);
}

}  // namespace
}  // namespace twinsim
