// What the diagnosis's verdict says about what is left, with and without a learned
// yardstick.
#include "diagnosis/diagnosis_report.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

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

// Issue 63: where the written model predicts worse than the given one at any horizon,
// and where the response changed part way, the verdict says so first.
TEST(DiagnosisVerdict, SaysFirstWhereTheWrittenModelIsWorseAndWhereTheResponseChanged) {
  DiagnosisReport r = OneUnexplainedAxis(true);
  DiagnosisHorizon h;
  h.predictors = {"given model", "identified model", "repaired model", "constant velocity"};
  h.rows = 40;
  for (const auto& [label, gaps] : std::vector<std::pair<std::string, std::vector<double>>>{
           {"4 frames", {0.010, 0.006, 0.006, 0.012}},   // better
           {"1 s", {0.100, 0.104, 0.104, 0.300}},        // 4 % worse: within the tolerance
           {"3 s", {0.500, 0.600, 0.620, 1.000}}}) {     // 24 % worse
    h.label = label;
    h.gaps = gaps;
    r.horizons.push_back(h);
  }
  r.caution = WorseThanGiven(r, 0.05);
  EXPECT_EQ(r.caution, "The written model predicts the test rows worse than the given one: 620 against 500 mm at 3 s. ");
  r.changes.push_back({"run.csv", 4.2, "velocity scale", 0.66, 0.27, 11.9,
                       "the velocity scale fell from 0.66 to 0.27 at t = 4.2 s"});
  const std::string verdict = DiagnosisVerdict(r);
  EXPECT_EQ(verdict.find(r.caution), 0u) << verdict;
  EXPECT_EQ(verdict.find("The response changes part way: run.csv: the velocity scale fell from 0.66 to 0.27 at t = "
                         "4.2 s"),
            r.caution.size())
      << verdict;
  r.horizons.pop_back();
  EXPECT_EQ(WorseThanGiven(r, 0.05), "");
}

}  // namespace
}  // namespace twinsim
