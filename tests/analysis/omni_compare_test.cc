#include "analysis/omni_compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "io/csv_table.h"
#include "learning/omni_predictor.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

// A log recorded from `model` on the analytic backend, without camera noise.
OmniLog RecordLog(OmniModel model, double seconds) {
  model.vision_noise_xy = model.vision_noise_theta = 0;
  return testing::RecordLog(model, testing::RandomDrive(1.5, 0, 0), seconds, 21);
}

OmniCompareOptions AnalyticAtDefaultHorizons() {
  OmniCompareOptions options;
  options.sources = {{"analytic", "analytic", {}}};
  options.horizons = DefaultCompareHorizons(30);
  return options;
}

std::string InputErrorOf(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& options) {
  try {
    CompareOmniLog(model, log, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(OmniCompare, DefaultHorizonsRunFromOneFrameToThreeSecondsAndFreeRun) {
  EXPECT_EQ(DefaultCompareHorizons(30), (std::vector<int>{1, 4, 8, 30, 90, 0}));
  EXPECT_EQ(DefaultCompareHorizons(59.94), (std::vector<int>{1, 4, 15, 60, 180, 0}));
  EXPECT_EQ(DefaultCompareHorizons(16), (std::vector<int>{1, 4, 16, 48, 0}));  // 0.25 s is 4 frames
  EXPECT_EQ(HorizonLabel(1, 30), "1 frame");
  EXPECT_EQ(HorizonLabel(4, 30), "4 frames");
  EXPECT_EQ(HorizonLabel(8, 30), "0.25 s");
  EXPECT_EQ(HorizonLabel(30, 30), "1 s");
  EXPECT_EQ(HorizonLabel(90, 30), "3 s");
  EXPECT_EQ(HorizonLabel(0, 30), "free run");
}

TEST(OmniCompare, TheRecordingModelPredictsItsOwnLogAtEveryHorizon) {
  // An ideal encoder: with counts, the CSV's rounding (1e-9) of the measured poses
  // flips a count now and then, and the controller's reaction to it shows as ~1e-6 m.
  OmniModel model = testing::Omni4();
  model.encoder_counts_per_rev = 0;
  const OmniLog log = RecordLog(model, 8);
  const OmniCompareResult r = CompareOmniLog(model, log, AnalyticAtDefaultHorizons());
  ASSERT_EQ(r.rows.size(), 6u);
  for (const CompareErrorRow& row : r.rows) {
    EXPECT_EQ(row.source, "analytic");
    EXPECT_GT(row.predicted, row.horizon_frames > 30 ? 30 : 100) << row.horizon;  // 3 s: every 3rd frame
    // Only the CSV's rounding (1e-9) separates the replay from the recording, and the
    // frames at rest, where the noise-free camera repeats its pose: no new measurement
    // (CONTRACT.md), so the tracker runs on its own state there. A free run carries it
    // all along without correction.
    const double tolerance = row.horizon_frames == 0 || row.horizon_frames > 30 ? 1e-3 : 2e-4;
    EXPECT_LT(row.position_rmse, tolerance) << row.horizon;
    EXPECT_LT(row.position_max, tolerance) << row.horizon;
    EXPECT_LT(row.heading_rmse, tolerance) << row.horizon;
  }
  EXPECT_EQ(r.Find("analytic", 0)->predicted, log.num_measured() - 1);  // scored where measured

  // The wrong delay shows at 4 frames: the commands act 4 frames early.
  OmniModel no_delay = model;
  no_delay.command_delay_frames = no_delay.vision_delay_frames = 0;
  OmniCompareOptions four = AnalyticAtDefaultHorizons();
  four.horizons = {4};
  const CompareErrorRow wrong = CompareOmniLog(no_delay, log, four).rows.at(0);
  EXPECT_GT(wrong.position_rmse, 1e-3) << "delay 0 predicts 4 frames ahead to " << wrong.position_rmse << " m";
  EXPECT_GT(wrong.position_rmse, 1000 * r.Find("analytic", 4)->position_rmse);
}

TEST(OmniCompare, ErrorsGrowWithTheHorizonForAMismatchedModel) {
  // The plant has effects (delay, lag, scale, drift, saturation) the model lacks.
  const OmniLog log = RecordLog(LoadOmniModel(testing::SourcePath("models/omni4_plant.yaml")), 8);
  const OmniCompareResult r = CompareOmniLog(testing::Omni4(), log, AnalyticAtDefaultHorizons());
  const double one = r.Find("analytic", 1)->position_rmse;
  const double four = r.Find("analytic", 4)->position_rmse;
  const double second = r.Find("analytic", 30)->position_rmse;
  EXPECT_LT(one, four);
  EXPECT_LT(four, second);
  EXPECT_GT(second, 0.01) << "1 s ahead, a 15 % speed error alone is centimetres";
  EXPECT_LT(r.Find("analytic", 1)->heading_rmse, r.Find("analytic", 30)->heading_rmse);
  for (const CompareErrorRow& row : r.rows) EXPECT_LE(row.position_rmse, row.position_max) << row.horizon;
}

// The no-model baselines are scored on the rows the first source predicts, at every
// horizon but the free run; the options a user gets leave out horizons the log is too
// short for.
TEST(OmniCompare, BaselinesShareTheFirstSourcesRowsAndShortLogsDropLongHorizons) {
  const OmniLog log = RecordLog(LoadOmniModel(testing::SourcePath("models/omni4_plant.yaml")), 8);
  OmniCompareOptions options = AnalyticAtDefaultHorizons();
  options.baselines = true;
  const OmniCompareResult r = CompareOmniLog(testing::Omni4(), log, options);
  ASSERT_EQ(r.rows.size(), 6u + 2 * 5);
  for (int k : options.horizons) {
    const CompareErrorRow* model = r.Find("analytic", k);
    ASSERT_TRUE(model);
    for (const char* name : {"constant_velocity", "integrated_command"}) {
      const CompareErrorRow* b = r.Find(name, k);
      if (k == 0) {
        EXPECT_FALSE(b);
        continue;
      }
      ASSERT_TRUE(b) << name << " " << k;
      EXPECT_EQ(b->backend, "baseline");
      EXPECT_EQ(b->predicted, model->predicted) << name << " " << k;
      EXPECT_GT(b->position_rmse, 0) << name << " " << k;
    }
  }
  // A frame ahead, the camera's last two poses are hard to beat; a second ahead, the
  // constant velocity of a robot that changes its command every few tenths is far off.
  EXPECT_LT(r.Find("constant_velocity", 1)->position_rmse, r.Find("constant_velocity", 30)->position_rmse / 10);

  const OmniCompareOptions made = MakeCompareOptions(testing::Omni4(), RecordLog(testing::Omni4(), 3), {"analytic"}, nullptr);
  EXPECT_EQ(made.horizons, (std::vector<int>{1, 4, 8, 30, 0}));
  EXPECT_TRUE(made.baselines);
}

TEST(OmniCompare, CsvsHaveOneRowPerSourceAndHorizonAndOnePathRowPerLogRow) {
  const OmniModel model = testing::Omni4();
  const OmniLog log = RecordLog(model, 3);
  OmniCompareOptions options = AnalyticAtDefaultHorizons();
  options.horizons = {1, 4, 30, 0};  // the 3 s log is too short for 3 s
  options.sources.push_back({"again", "analytic", {}});
  const OmniCompareResult r = CompareOmniLog(model, log, options);

  std::istringstream errors(FormatCompareErrorsCsv(r));
  std::vector<std::string> lines;
  for (std::string line; std::getline(errors, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 1u + 2 * 4);
  EXPECT_EQ(lines[0], "source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse");
  EXPECT_EQ(lines[1].rfind("analytic,analytic,1 frame,1,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[7].rfind("again,analytic,1 s,30,", 0), 0u) << lines[7];
  EXPECT_EQ(lines[8].rfind("again,analytic,free run,0,", 0), 0u) << lines[8];

  const CsvTable paths = ParseCsvTable(FormatComparePathsCsv(log, r), "paths.csv");
  EXPECT_EQ(paths.header, (std::vector<std::string>{"t", "measured_x", "measured_y", "measured_theta", "analytic_x",
                                                    "analytic_y", "analytic_theta", "again_x", "again_y",
                                                    "again_theta"}));
  ASSERT_EQ(paths.rows.size(), log.rows.size());
  EXPECT_NEAR(paths.rows.back()[4], log.rows.back().pose.x, 1e-3);

  const std::string report = r.FullReport();
  EXPECT_NE(report.find("free run"), std::string::npos) << report;
  EXPECT_NE(report.find("again"), std::string::npos) << report;
}

TEST(OmniCompare, BadOptionsAreInputErrorsNamingTheProblem) {
  const OmniModel model = testing::Omni4();
  const OmniLog log = RecordLog(model, 1.5);
  OmniCompareOptions options = AnalyticAtDefaultHorizons();
  options.sources = {{"warp", "warp", {}}};
  options.horizons = {1};
  EXPECT_NE(InputErrorOf(model, log, options).find("unknown physics backend 'warp'"), std::string::npos);
  options.sources = {{"a", "analytic", {}}, {"a", "analytic", {}}};
  EXPECT_NE(InputErrorOf(model, log, options).find("source 'a' given twice"), std::string::npos);
  options.sources = {{"learned", "learned", {}}};
  EXPECT_NE(InputErrorOf(model, log, options).find("needs a predictor"), std::string::npos);
  // 46 frames cannot hold delay 4 + warm-up 15 + 30 frames ahead.
  options.sources = {{"analytic", "analytic", {}}};
  options.horizons = {30};
  EXPECT_NE(InputErrorOf(model, log, options).find("recorded.csv: log of 46 frames is too short to compare at the 1 s"),
            std::string::npos)
      << InputErrorOf(model, log, options);
}

// The command line: files, rows, exit codes.
class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = testing::TempDir("compare_cli");
    log_path = dir + "/log.csv";
    const OmniLog log = RecordLog(testing::Omni4(), 4);
    WriteOmniLog(log_path, log.rows);
  }
  std::string Predictor(const std::string& model_name) {
    OmniModel model = testing::Omni4();
    model.name = model_name;
    const std::string path = dir + "/" + model_name + ".pred";
    TrainOmniPredictor(model, {ReadOmniLog(log_path)}, OmniTrainOptions{}).Save(path);
    return path;
  }
  std::string Args(const std::string& out) const {
    return "compare --model " + testing::SourcePath("models/omni4.yaml") + " --log " + log_path + " --out " + out;
  }
  std::string dir, log_path;
};

TEST_F(CompareCli, WritesErrorsForEveryBackendAndHorizonAndThePaths) {
  const std::string out = dir + "/out";
  auto r = testing::RunTwinsim(Args(out) + " --backend analytic --backend learned --predictor " + Predictor("omni4"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string errors = testing::ReadText(out + "/errors.csv");
  EXPECT_EQ(errors.rfind("source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse\n", 0),
            0u)
      << errors;
  // The 4 s log holds 1, 4 frames, 0.25, 1 and 3 s and the free run; the baselines all but the free run.
  EXPECT_EQ(std::count(errors.begin(), errors.end(), '\n'), 1 + 2 * 6 + 2 * 5) << errors;
  EXPECT_NE(errors.find("\nconstant_velocity,baseline,3 s,90,"), std::string::npos) << errors;
  EXPECT_NE(errors.find("\nintegrated_command,baseline,0.25 s,8,"), std::string::npos) << errors;
  EXPECT_NE(errors.find("\nlearned,learned,free run,0,"), std::string::npos) << errors;
  const std::string paths = testing::ReadText(out + "/paths.csv");
  EXPECT_EQ(paths.rfind("t,measured_x,measured_y,measured_theta,analytic_x,analytic_y,analytic_theta,learned_x,", 0), 0u);
  EXPECT_NE(r.out.find("free run"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out + "/errors.csv"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out + "/paths.csv"), std::string::npos) << r.out;

  auto help = testing::RunTwinsim("compare --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("free run"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("paths.csv"), std::string::npos) << help.out;
}

TEST_F(CompareCli, BadBackendIsBadInputAndWritesNothing) {
  const std::string out = dir + "/out";
  auto r = testing::RunTwinsim(Args(out) + " --backend analytic --backend warp");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown physics backend 'warp'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CompareCli, PredictorForAnotherModelIsBadInputAndWritesNothing) {
  const std::string out = dir + "/out";
  const std::string predictor = Predictor("omni4_other");
  auto r = testing::RunTwinsim(Args(out) + " --backend analytic --predictor " + predictor);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(predictor + ": predictor was trained for model 'omni4_other', not 'omni4'"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace twinsim
