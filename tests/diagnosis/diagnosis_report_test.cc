// What the diagnosis's verdict says about what is left, with and without a learned
// yardstick.
#include "diagnosis/diagnosis_report.h"

#include <gtest/gtest.h>

namespace twinsim {
namespace {

// A report with one axis far above its noise that no learned correction shrinks.
DiagnosisReport OneUnexplainedAxis(bool yardstick) {
  DiagnosisReport r;
  r.robot = "omni";
  r.gap_before = r.gap_after = 0.012;
  r.noise_floor = 0.001;
  ChannelAdequacy a;
  a.channel = "sideways";
  a.rms = 0.01;
  a.noise = 0.0001;
  a.above_floor = a.unexplained = true;
  r.adequacy.push_back(a);
  r.yardstick.available = yardstick;
  r.yardstick.learner = yardstick ? "the seed's linear predictor as a residual"
                                  : "no learned residual: log too short: 150 rows give 34 complete windows";
  r.yardstick.physics_share = yardstick ? 0.5 : std::numeric_limits<double>::quiet_NaN();
  return r;
}

TEST(DiagnosisVerdict, SaysWhenNoLearnedYardstickCouldBeComputed) {
  const std::string without = DiagnosisVerdict(OneUnexplainedAxis(false));
  EXPECT_EQ(without.find("no learned residual of the motion predicts it"), std::string::npos) << without;
  EXPECT_NE(without.find("whether it is predictable is not known"), std::string::npos) << without;
  EXPECT_NE(without.find("log too short"), std::string::npos) << without;
  EXPECT_EQ(without.find("The named physics explains"), std::string::npos) << without;

  const std::string with = DiagnosisVerdict(OneUnexplainedAxis(true));
  EXPECT_NE(with.find("no learned residual of the motion predicts it"), std::string::npos) << with;
  EXPECT_NE(with.find("The named physics explains 50 %"), std::string::npos) << with;
}

}  // namespace
}  // namespace twinsim
