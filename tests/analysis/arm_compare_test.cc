// `compare` for arms: models on backends simulated from a log's torques, side by side,
// with their free runs for the plot of simulated against measured motion.
#include "analysis/arm_compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "analysis/ode_pd_arm_log.h"
#include "core/error.h"
#include "io/csv_table.h"
#include "test_util.h"

namespace twinsim {
namespace {

ArmModel RrrForCompare() { return LoadArmModel(testing::SourcePath("models/rrr.yaml")); }

ArmModel Heavier(ArmModel model, double scale) {
  for (ArmJoint& j : model.joints) j.child.mass *= scale, j.child.inertia *= scale;
  return model;
}

TEST(ArmCompare, TheTruthBeatsAWrongModelAtEveryHorizonAndTheFreeRunIsKept) {
  const ArmModel truth = RrrForCompare();
  const ArmLog log = testing::OdePdArmLog(truth, 3.0, 2);  // 500 Hz, from ODE
  ArmCompareOptions options;
  options.horizons = {0.1, 0.5, 5.0, 0};  // 5 s does not fit the log: left out
  const ArmCompareResult r =
      CompareArmLog(log, {{"truth", truth, "analytic", {}}, {"heavy (1.3)", Heavier(truth, 1.3), "analytic", {}}}, options);
  ASSERT_EQ(r.scores.size(), 2u);
  const ArmSimulationScore& right = r.scores[0].second;
  const ArmSimulationScore& wrong = r.scores[1].second;
  ASSERT_EQ(right.horizons.size(), 3u);
  EXPECT_EQ(right.horizons[0].horizon, 0.1);
  EXPECT_EQ(right.horizons[1].horizon, 0.5);
  EXPECT_EQ(right.horizons[2].horizon, 0);
  for (std::size_t h = 0; h < 3; ++h) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_LT(right.horizons[h].rmse[j], 0.5 * wrong.horizons[h].rmse[j]) << "horizon " << h << " joint " << j + 1;
    }
  }
  // 0.1 s ahead the model that made the log beats no model by far (measured 3e-5 rad
  // against 0.015 to 0.025 for constant velocity, arm_simulation_score_test.cc).
  EXPECT_LT(right.horizons[0].rmse.maxCoeff(), 0.1 * right.horizons[0].constant_velocity.minCoeff());

  // The free run: one window over the log, kept row by row.
  ASSERT_GE(right.free_run_start, 0);
  EXPECT_EQ(right.free_run.rows(), right.horizons[2].rows);
  const double free_rmse = std::sqrt(
      (right.free_run - log.q.middleRows(right.free_run_start + 1, right.free_run.rows())).col(1).squaredNorm() /
      right.free_run.rows());
  EXPECT_NEAR(free_rmse, right.horizons[2].rmse[1], 1e-12);

  // paths.csv: the measured q on every row, each source's free run where it runs.
  const CsvTable paths = ParseCsvTable(FormatArmComparePathsCsv(log, r), "paths.csv");
  ASSERT_EQ(paths.header, (std::vector<std::string>{"t", "measured_q1", "measured_q2", "measured_q3", "truth_q1",
                                                     "truth_q2", "truth_q3", "heavy__1_3__q1", "heavy__1_3__q2",
                                                     "heavy__1_3__q3"}));
  ASSERT_EQ(static_cast<int>(paths.rows.size()), log.rows());
  const int first = right.free_run_start + 1;
  EXPECT_TRUE(std::isnan(paths.rows[0][4]));  // before the run: an empty cell
  EXPECT_NEAR(paths.rows[first][2], log.q(first, 1), 1e-9);
  EXPECT_NEAR(paths.rows[first + 100][5], right.free_run(100, 1), 1e-9);
  EXPECT_NEAR(paths.rows[first + 100][8], wrong.free_run(100, 1), 1e-9);
}

TEST(ArmCompare, RefusesWhatCannotBeLaidSideBySide) {
  const ArmModel truth = RrrForCompare();
  const ArmLog log = testing::OdePdArmLog(truth, 0.6, 1);
  ArmCompareOptions options;
  options.horizons = {0.1};
  EXPECT_THROW(CompareArmLog(log, {}, options), InputError);
  EXPECT_THROW(CompareArmLog(log, {{"a", truth, "analytic", {}}, {"a", truth, "ode", {}}}, options), InputError);
  try {
    CompareArmLog(log, {{"a b", truth, "analytic", {}}, {"a_b", truth, "ode", {}}}, options);
    ADD_FAILURE() << "two sources with one column prefix were accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a_b_q1"), std::string::npos) << e.what();
  }
  options.horizons = {-0.1};
  EXPECT_THROW(CompareArmLog(log, {{"a", truth, "analytic", {}}}, options), InputError);
  options.horizons = {30.0};  // too long for the log, and nothing else asked for
  EXPECT_THROW(CompareArmLog(log, {{"a", truth, "analytic", {}}}, options), InputError);
}

TEST(ArmCompareCli, TwoModelsSideBySideWithTablesCsvsAndPlots) {
  const std::string dir = testing::TempDir("arm_compare_cli");
  const ArmModel truth = RrrForCompare();
  const std::string log = testing::WriteText(dir + "/arm.csv", FormatArmLog(testing::OdePdArmLog(truth, 2.0, 2), true));
  std::filesystem::copy_file(testing::SourcePath("models/rrr.yaml"), dir + "/other.yaml");
  const testing::CommandResult run =
      testing::RunTwinsim("compare --model " + testing::SourcePath("models/rrr.yaml") + " --model " + dir +
                          "/other.yaml --log " + log + " --horizon 0.1 --horizon 0 --out " + dir + "/out");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("rrr/analytic beats holding on 3 of 3 joints, constant velocity on 3 of 3"), std::string::npos)
      << run.out;
  const CsvTable errors = ReadCsvTable(dir + "/out/errors.csv");
  EXPECT_EQ(errors.rows.size(), 2u * 2u * 3u);  // sources x horizons x joints
  const CsvTable paths = ReadCsvTable(dir + "/out/paths.csv");
  EXPECT_EQ(paths.header.size(), 1u + 3u * 3u);
#ifdef TWINSIM_HAVE_OSMESA
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/paths.png"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/errors.png"));
#endif

  // Refused before anything runs or is written, exit 2.
  const std::string omni = testing::SourcePath("models/omni4.yaml");
  for (const std::string& bad :
       {"--model " + omni + " --model " + omni + " --log " + log,  // omni: one model
        "--model " + omni + " --log " + log + " --horizon 0.1",    // omni: fixed horizons
        "--model " + testing::SourcePath("models/rrr.yaml") + " --model " + omni + " --log " + log,
        "--model " + testing::SourcePath("models/rrr.yaml") + " --backend learned --log " + log,
        "--model " + testing::SourcePath("models/rrr.yaml") + " --backend nope --log " + log}) {
    const testing::CommandResult refused = testing::RunTwinsim("compare " + bad + " --out " + dir + "/refused");
    EXPECT_EQ(refused.exit_code, 2) << bad << "\n" << refused.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/refused")) << bad;
  }
}

}  // namespace
}  // namespace twinsim
