// `twinsim ilc` through the binary: trials.csv with the contract's columns, the other
// outputs, the learned backend, divergence as exit 1, and bad scene keys as exit 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "control/arm_trials.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::RunTwinsim;
using testing::SourcePath;

// The letter T on the stand-in arm, learning with the fitted filter.
std::string IlcScene(const std::string& dir, const std::string& plant, const std::string& ilc) {
  return testing::WriteText(dir + "/t.yaml",
                            "name: short_ilc\n"
                            "robot: arm\n"
                            "model: " + SourcePath(plant) + "\n"
                            "task: {type: writing, letters: T}\n"
                            "controller: {type: pd_feedforward, model: " + SourcePath("models/rrr.yaml") + "}\n"
                            "ilc:\n" + ilc);
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(IlcCli, WritesTrialsCsvWithTheContractColumnsAndTheReport) {
  const std::string dir = testing::TempDir("ilc_cli");
  const std::string scene = IlcScene(dir, "models/rrr_plant.yaml",
                                     "  trials: 4\n  gain: 0.5\n  frf: {periods: 2, amplitude: 0.3, postures: "
                                     "[[0.3, 0.9, -1.6], [-0.3, 0.6, -1.7]]}\n");
  auto r = RunTwinsim("ilc " + scene + " --out " + dir + "/out --trials 3");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("trial  3: RMS error"), std::string::npos) << r.out;
  const std::vector<std::string> lines = Lines(testing::ReadText(dir + "/out/trials.csv"));
  ASSERT_EQ(lines.size(), 5u);  // the header and trials 0..3 (--trials overrides the scene's 4)
  EXPECT_EQ(lines[0], "trial,rms1,rms2,rms3,max1,max2,max3");
  for (int k = 0; k <= 3; ++k) EXPECT_EQ(lines[static_cast<std::size_t>(k) + 1].rfind(std::to_string(k) + ",", 0), 0u);
  const std::vector<std::string> frf = Lines(testing::ReadText(dir + "/out/frf.csv"));
  EXPECT_EQ(frf[0], "joint,posture,frequency,magnitude,phase,coherence,filter_magnitude,filter_phase");
  EXPECT_EQ(frf.size(), 1u + 3 * 3 * 100);  // 3 joints x (the nominal + 2 postures) x the lines 2..200 Hz
  for (const char* file : {"filters.csv", "feedforward.csv", "report.html"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + file)) << file;
  }
  const std::string html = testing::ReadText(dir + "/out/report.html");
  EXPECT_EQ(html.find("http"), std::string::npos);  // nothing to fetch
  // Same inputs, same bytes.
  auto again = RunTwinsim("ilc " + scene + " --out " + dir + "/again --trials 3 --quiet");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.out, "");
  EXPECT_EQ(testing::ReadText(dir + "/again/trials.csv"), testing::ReadText(dir + "/out/trials.csv"));
  EXPECT_EQ(testing::ReadText(dir + "/again/feedforward.csv"), testing::ReadText(dir + "/out/feedforward.csv"));
}

// ILC on the learned arm backend, built by the same factory as `run`'s: a residual
// predictor of the plant learned from its own trials (so nearly the plant itself) learns
// the task as the plant's own analytic backend does.
TEST(IlcCli, LearnsOnTheLearnedBackendWithAPredictor) {
  const std::string dir = testing::TempDir("ilc_learned");
  const ArmModel plant = LoadArmModel(SourcePath("models/rrr_plant.yaml"));
  const ArmModel hat = LoadArmModel(SourcePath("models/rrr.yaml"));
  TrainingTrialOptions trials;
  trials.seconds = 10;
  const std::vector<ArmLog> logs = RecordTrainingTrials(plant, hat, trials, 2, 5);
  WriteArmLog(dir + "/a.csv", logs[0], true);
  WriteArmLog(dir + "/b.csv", logs[1], true);
  auto trained = RunTwinsim("train --quiet --model " + SourcePath("models/rrr_plant.yaml") + " --log " + dir +
                            "/a.csv --log " + dir + "/b.csv --kind linear --residual --out " + dir + "/plant.pred");
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  const std::string scene = IlcScene(dir, "models/rrr_plant.yaml",
                                     "  trials: 4\n  gain: 0.5\n  frf: {periods: 2, amplitude: 0.3, postures: "
                                     "[[0.3, 0.9, -1.6], [-0.3, 0.6, -1.7]]}\n");
  auto learned = RunTwinsim("ilc " + scene + " --quiet --backend learned --predictor " + dir + "/plant.pred --out " + dir +
                            "/learned");
  ASSERT_EQ(learned.exit_code, 0) << learned.err;
  auto analytic = RunTwinsim("ilc " + scene + " --quiet --out " + dir + "/analytic");
  ASSERT_EQ(analytic.exit_code, 0) << analytic.err;
  // The worst joint's RMS error, first and last trial.
  auto worst = [&](const std::string& folder, int trial) {
    const std::vector<std::string> lines = Lines(testing::ReadText(dir + "/" + folder + "/trials.csv"));
    std::istringstream row(lines.at(static_cast<std::size_t>(trial) + 1));
    std::string cell;
    std::getline(row, cell, ',');
    double w = 0;
    for (int j = 0; j < 3 && std::getline(row, cell, ','); ++j) w = std::max(w, std::stod(cell));
    return w;
  };
  const double gain_learned = worst("learned", 0) / worst("learned", 4);
  const double gain_analytic = worst("analytic", 0) / worst("analytic", 4);
  EXPECT_GT(gain_learned, 0.5 * gain_analytic) << "learned " << gain_learned << "x, analytic " << gain_analytic << "x";
  EXPECT_GT(gain_learned, 3) << worst("learned", 0) << " -> " << worst("learned", 4) << " rad";
  EXPECT_NEAR(worst("learned", 0), worst("analytic", 0), 0.2 * worst("analytic", 0)) << "trial 0, no learning";

  // Without a predictor, or a predictor for another backend, as `run` says.
  auto none = RunTwinsim("ilc " + scene + " --backend learned --out " + dir + "/none");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("--backend learned needs --predictor P"), std::string::npos) << none.err;
  auto stray = RunTwinsim("ilc " + scene + " --predictor " + dir + "/plant.pred --out " + dir + "/stray");
  EXPECT_EQ(stray.exit_code, 2);
  EXPECT_NE(stray.err.find("--predictor applies to --backend learned only"), std::string::npos) << stray.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/none"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/stray"));
}

TEST(IlcCli, DivergingLearningExitsOne) {
  const std::string dir = testing::TempDir("ilc_cli_diverge");
  // The flexible elbow without a robustness filter.
  const std::string scene =
      IlcScene(dir, "models/rrr_plant_flex.yaml", "  trials: 5\n  gain: 0.5\n  q_order: 0\n  frf: {periods: 2, amplitude: 0.3}\n");
  auto r = RunTwinsim("ilc " + scene + " --out " + dir + "/out --quiet");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("ILC diverged"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/trials.csv"));
}

TEST(IlcCli, BadIlcKeysExitTwoWithFileLineColumn) {
  const std::string dir = testing::TempDir("ilc_cli_bad");
  const std::string scene = IlcScene(dir, "models/rrr_plant.yaml",
                                     "  trials: 4\n  gian: 0.5\n  learning_filter: magic\n  frf: {band: [50, 10], postures: [[1, 2]]}\n");
  auto r = RunTwinsim("ilc " + scene + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(scene + ":8:3: "), std::string::npos) << r.err;   // gian
  EXPECT_NE(r.err.find("unknown key 'gian'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("magic"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("low < high"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected 3 joint positions"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trials.csv"));
}

TEST(IlcCli, FrequencyResponsesThatCannotBeMeasuredExitTwo) {
  // Scene values the reader cannot judge alone (they need the model's sample time) are
  // bad input too: exit 2 with the reason, not an internal error.
  const std::string dir = testing::TempDir("ilc_cli_frf");
  struct Case {
    std::string frf, expected;
  };
  const std::vector<Case> cases = {
      {"{period: 0.002}", "MeasureProcessSensitivity: the period is shorter than 4 samples"},
      {"{band: [600, 900]}", "Hz lies in [600.000000, 900.000000] Hz below the Nyquist frequency"},
  };
  for (const Case& c : cases) {
    const std::string scene = IlcScene(dir, "models/rrr_plant.yaml", "  trials: 1\n  frf: " + c.frf + "\n");
    auto r = RunTwinsim("ilc " + scene + " --out " + dir + "/out --quiet");
    EXPECT_EQ(r.exit_code, 2) << c.frf << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace twinsim
