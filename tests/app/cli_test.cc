// The command line as users and scripts see it: exit codes, messages, files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "io/csv_table.h"
#include "robots/omni/omni_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::ReadText;
using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;
using testing::WriteText;
namespace fs = std::filesystem;

TEST(Cli, HelpDescribesEveryCommand) {
  auto r = RunTwinsim("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("run"), std::string::npos);
  EXPECT_NE(r.out.find("replay"), std::string::npos);
  for (const char* cmd : {"run", "replay", "compare", "diagnose", "batch"}) {
    auto c = RunTwinsim(std::string(cmd) + " --help");
    EXPECT_EQ(c.exit_code, 0) << cmd;
    EXPECT_NE(c.out.find("--out"), std::string::npos) << cmd;
  }
}

TEST(Cli, UnknownOptionIsBadInput) {
  EXPECT_EQ(RunTwinsim("run --frobnicate x").exit_code, 2);
  EXPECT_EQ(RunTwinsim("").exit_code, 2);
}

TEST(Cli, RunWritesTheContractLogAndIsDeterministic) {
  const std::string a = TempDir("run_a"), b = TempDir("run_b");
  const std::string scene = SourcePath("scenes/drive45.yaml");
  auto r1 = RunTwinsim("run " + scene + " --backend analytic --out " + a + " --seed 5");
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  EXPECT_NE(r1.out.find(a + "/trajectory.csv"), std::string::npos) << r1.out;
  auto r2 = RunTwinsim("run " + scene + " --backend analytic --out " + b + " --seed 5 --quiet");
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  const std::string log = ReadText(a + "/trajectory.csv");
  EXPECT_EQ(log.rfind("t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n", 0), 0u);
  EXPECT_EQ(log, ReadText(b + "/trajectory.csv"));
  const OmniLog parsed = ReadOmniLog(a + "/trajectory.csv");
  EXPECT_EQ(parsed.rows.size(), 121u);
}

TEST(Cli, BadSceneIsExitTwoWithFileAndLine) {
  const std::string dir = TempDir("bad_scene");
  const std::string scene = WriteText(dir + "/s.yaml", "name: s\nduration: 1\nrobots: []\nfoo: 1\n");
  auto r = RunTwinsim("run " + scene + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(scene + ":3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(scene + ":4:1: unknown key 'foo'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

TEST(Cli, UncompiledOrUnknownBackendIsBadInput) {
  const std::string dir = TempDir("bad_backend");
  auto r = RunTwinsim("run " + SourcePath("scenes/drive45.yaml") + " --backend warp --out " + dir + "/o");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown physics backend 'warp'"), std::string::npos) << r.err;
}

TEST(Cli, ReplayWithBadLogLeavesNothingBehind) {
  const std::string dir = TempDir("bad_replay");
  const std::string log = WriteText(dir + "/bad.csv", "t,x\n0,abc\n");
  auto r = RunTwinsim("replay --model " + SourcePath("models/omni4.yaml") + " --log " + log + " --out " + dir + "/o.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(log + ":2:3: column 'x': expected a number, got 'abc'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/o.csv"));
  auto missing = RunTwinsim("replay --model " + dir + "/missing.yaml --log " + log + " --out " + dir + "/o.csv");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(dir + "/missing.yaml: cannot open file"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(dir + "/o.csv"));
}

TEST(Cli, ReplayWritesOneRowPerInputRow) {
  const std::string dir = TempDir("replay");
  ASSERT_EQ(RunTwinsim("run " + SourcePath("scenes/steps.yaml") + " --backend analytic --quiet --out " + dir).exit_code, 0);
  auto r = RunTwinsim("replay --model " + SourcePath("models/omni4.yaml") + " --log " + dir +
                      "/trajectory.csv --backend analytic --out " + dir + "/replay.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string out = ReadText(dir + "/replay.csv");
  EXPECT_EQ(out.rfind("t,x,y,theta\n", 0), 0u);
  const OmniLog in = ReadOmniLog(dir + "/trajectory.csv");
  EXPECT_EQ(static_cast<std::size_t>(std::count(out.begin(), out.end(), '\n')), in.rows.size() + 1);
  EXPECT_NE(r.out.find("state from the observer"), std::string::npos) << r.out;
  // --state's words reach the replay; others (the enum's numbers too) are refused.
  auto tracked = RunTwinsim("replay --model " + SourcePath("models/omni4.yaml") + " --log " + dir +
                            "/trajectory.csv --backend analytic --state tracker --out " + dir + "/tracked.csv");
  ASSERT_EQ(tracked.exit_code, 0) << tracked.err;
  EXPECT_NE(tracked.out.find("state from the tracker"), std::string::npos) << tracked.out;
  EXPECT_NE(ReadText(dir + "/tracked.csv"), out);
  for (const char* word : {"kalman", "1"}) {
    auto bad = RunTwinsim("replay --model " + SourcePath("models/omni4.yaml") + " --log " + dir +
                          "/trajectory.csv --state " + word + " --out " + dir + "/bad.csv");
    EXPECT_EQ(bad.exit_code, 2) << word;
    EXPECT_NE(bad.err.find(std::string("--state: must be observer or tracker, got '") + word + "'"), std::string::npos)
        << bad.err;
    EXPECT_FALSE(fs::exists(dir + "/bad.csv"));
  }
}

// Issue 63: a model fitted on one engine is replayed there unless told otherwise, and the
// replay says so when told; the same bytes as that engine asked by name.
TEST(Cli, ReplayUsesTheEngineTheModelWasFittedOnAndSaysWhenToldOtherwise) {
  const std::string dir = TempDir("replay_fitted_on");
  ASSERT_EQ(RunTwinsim("run " + SourcePath("scenes/steps.yaml") + " --backend analytic --quiet --out " + dir).exit_code, 0);
  WriteText(dir + "/fitted.yaml", "extends: " + SourcePath("models/omni4.yaml") + "\nfitted_on: analytic\n");
  const std::string replay = "replay --model " + dir + "/fitted.yaml --log " + dir + "/trajectory.csv --out ";
  const auto plain = RunTwinsim(replay + dir + "/plain.csv");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.out.find(" on analytic "), std::string::npos) << plain.out;
  EXPECT_EQ(plain.err.find("fitted_on"), std::string::npos) << plain.err;
  const auto named = RunTwinsim(replay + dir + "/named.csv --backend analytic");
  ASSERT_EQ(named.exit_code, 0) << named.err;
  EXPECT_EQ(ReadText(dir + "/plain.csv"), ReadText(dir + "/named.csv"));
  const auto other = RunTwinsim(replay + dir + "/ode.csv --backend ode --quiet");
  ASSERT_EQ(other.exit_code, 0) << other.err;
  EXPECT_NE(other.err.find("note: omni4 was fitted on the analytic engine (fitted_on); replaying it on ode as asked"),
            std::string::npos)
      << other.err;
}

namespace twinsim {
namespace {

TEST(CliLearning, TrainRefusesALogTooShortAndWritesNothing) {
  const std::string dir = testing::TempDir("train_short");
  ASSERT_EQ(testing::RunTwinsim("run " + testing::SourcePath("scenes/drive45.yaml") +
                                " --backend analytic --quiet --out " + dir)
                .exit_code,
            0);
  // drive45 is 4 s: enough rows, but cut it to half a second.
  std::string log = testing::ReadText(dir + "/trajectory.csv");
  std::string cut;
  int lines = 0;
  for (std::size_t i = 0; i < log.size() && lines < 16; ++i) {
    cut += log[i];
    if (log[i] == '\n') ++lines;
  }
  testing::WriteText(dir + "/short.csv", cut);
  auto r = testing::RunTwinsim("train --model " + testing::SourcePath("models/omni4.yaml") + " --log " + dir +
                               "/short.csv --kind linear --horizon 1 --out " + dir + "/p.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(dir + "/short.csv: log too short"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/p.pred"));
  auto bad_kind = testing::RunTwinsim("train --model " + testing::SourcePath("models/omni4.yaml") + " --log " + dir +
                                      "/trajectory.csv --kind forest --out " + dir + "/p.pred");
  EXPECT_EQ(bad_kind.exit_code, 2);
}

TEST(CliLearning, LearnedBackendRefusesAPredictorForAnotherRobot) {
  const std::string dir = testing::TempDir("learned_mismatch");
  auto r = testing::RunTwinsim("run " + testing::SourcePath("scenes/figure_eight.yaml") +
                               " --backend learned --predictor " +
                               testing::SourcePath("models/predictors/omni4_h4.pred") + " --out " + dir + "/o");
  EXPECT_EQ(r.exit_code, 2);
  // figure_eight drives omni3 at 60 fps; the shipped predictor is omni4's at 30 fps.
  EXPECT_NE(r.err.find("predictor was trained for model 'omni4', not 'omni3'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/o"));
  auto none = testing::RunTwinsim("run " + testing::SourcePath("scenes/drive45.yaml") + " --backend learned --out " +
                                  dir + "/o");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("the learned backend needs a predictor: pass --predictor FILE"), std::string::npos)
      << none.err;
}

TEST(CliLearning, ResidualPredictorTrainsRunsAndComparesFromTheCommandLine) {
  const std::string dir = testing::TempDir("residual_cli");
  const std::string omni4 = testing::SourcePath("models/omni4.yaml");
  ASSERT_EQ(testing::RunTwinsim("run " + testing::SourcePath("scenes/random_excitation.yaml") +
                                " --backend analytic --quiet --out " + dir + "/drive")
                .exit_code,
            0);
  const std::string log = dir + "/drive/trajectory.csv";
  auto trained = testing::RunTwinsim("train --no-noise --model " + omni4 + " --log " + log +
                                     " --kind linear --residual --out " + dir + "/residual.pred");
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  EXPECT_NE(trained.out.find("residual linear predictor of omni4, over its Newtonian model on analytic"),
            std::string::npos)
      << trained.out;
  EXPECT_EQ(testing::ReadText(dir + "/residual.pred").rfind("twinsim_predictor: 3\n", 0), 0u);
  // A one-frame predictor carries the learned backend's driving noise, fitted on the
  // held-out rows (issue 42), unless --no-noise.
  EXPECT_EQ(testing::ReadText(dir + "/residual.pred").find("driving_noise"), std::string::npos);
  auto seed = testing::RunTwinsim("train --model " + omni4 + " --log " + log + " --kind linear --out " + dir + "/seed.pred");
  ASSERT_EQ(seed.exit_code, 0) << seed.err;
  EXPECT_NE(seed.out.find("on the held-out rows, driving noise: forward"), std::string::npos) << seed.out;
  // And its intervals' safeguard on the same rows, said as a table (issue 64).
  EXPECT_NE(seed.out.find("intervals' safeguard (a conformal scale of the rollouts' spread, fitted on the held-out rows, "
                          "each log's halves as folds"),
            std::string::npos)
      << seed.out;
  EXPECT_NE(seed.out.find("  63 frames ("), std::string::npos) << seed.out;
  EXPECT_NE(testing::ReadText(dir + "/seed.pred").find("\ndriving_noise: {forward: "), std::string::npos);
  EXPECT_EQ(testing::ReadText(dir + "/seed.pred").rfind("twinsim_predictor: 2\n", 0), 0u)
      << "the seed's predictors keep the format older builds read";

  // It runs where a learned predictor runs.
  auto run = testing::RunTwinsim("run " + testing::SourcePath("scenes/drive45.yaml") +
                                 " --backend learned --quiet --predictor " + dir + "/residual.pred --out " + dir + "/run");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  auto compare = testing::RunTwinsim("compare --quiet --model " + omni4 + " --log " + log +
                                     " --backend analytic --backend learned --predictor " + dir +
                                     "/seed.pred --predictor " + dir + "/residual.pred --out " + dir + "/compare");
  ASSERT_EQ(compare.exit_code, 0) << compare.err;
  const std::string errors = testing::ReadText(dir + "/compare/errors.csv");
  EXPECT_NE(errors.find("\nlearned,learned,4 frames,"), std::string::npos) << errors;
  EXPECT_NE(errors.find("\nresidual,learned,4 frames,"), std::string::npos) << errors;
  // The physics source's predictive distribution (the observer's) and the seed
  // predictor's (its sampled rollouts); the residual one, without a noise, none.
  const std::string calibration_csv = testing::ReadText(dir + "/compare/calibration.csv");
  CsvTable calibration = ParseCsvTable(calibration_csv, "calibration.csv");
  ASSERT_EQ(calibration.header.size(), 14u);
  EXPECT_EQ(calibration.header[5], "position_50");
  ASSERT_EQ(calibration.rows.size(), 6u);  // analytic, then learned, at 4, 16 and 63 frames
  EXPECT_NE(calibration_csv.find("\nlearned,learned,63,"), std::string::npos) << calibration_csv;
  for (std::size_t i = 3; i < 6; ++i) {
    EXPECT_GT(calibration.rows[i][4], 100) << "rows";
    EXPECT_GT(calibration.rows[i][6], 0.5) << "the 90 % ellipses of a noise fitted on held-out rows";
  }
  calibration.rows.resize(3);
  for (const auto& row : calibration.rows) {
    EXPECT_GT(row[4], 100) << "rows";
    // The log is the model's own plant with no driving noise, the model's default noise
    // 0.1 m/s: its ellipses are far too wide, and hold nearly every position.
    EXPECT_GT(row[5], 0.9);
    EXPECT_GE(row[6], row[5]);
    EXPECT_LE(row[6], 1.0);
  }
  EXPECT_EQ(calibration_csv.find("\nresidual,"), std::string::npos);
  // The same rows by quarter of the log's turn rate: four quarters of each source and
  // horizon, a quarter of each horizon's rows each (give or take one), slowest first.
  const CsvTable by_turn = ParseCsvTable(testing::ReadText(dir + "/compare/calibration_by_turn_rate.csv"), "by turn");
  ASSERT_EQ(by_turn.header.size(), 17u);
  EXPECT_EQ(by_turn.header[3], "turn_rate_from");
  ASSERT_EQ(by_turn.rows.size(), 24u);  // analytic, then learned, each 4 quarters x 3 horizons
  for (std::size_t i = 0; i < 12; ++i) {
    const std::size_t h = i % 3, quarter = i / 3;
    EXPECT_EQ(by_turn.rows[i][2], static_cast<double>(quarter + 1));
    EXPECT_NEAR(by_turn.rows[i][7], calibration.rows[h][4] / 4, 1) << i;  // rows
    EXPECT_LE(by_turn.rows[i][3], by_turn.rows[i][4]) << i;
    if (quarter > 0) {
      EXPECT_GE(by_turn.rows[i][3], by_turn.rows[i - 3][4]) << i;
    }
  }

  // Its rollouts sampled: replay writes t,sample,x,y,theta, three rows per input row.
  auto sampled = testing::RunTwinsim("replay --model " + omni4 + " --log " + log + " --backend learned --predictor " + dir +
                                     "/seed.pred --samples 3 --horizon 8 --out " + dir + "/sampled.csv");
  ASSERT_EQ(sampled.exit_code, 0) << sampled.err;
  const std::string sampled_csv = testing::ReadText(dir + "/sampled.csv");
  EXPECT_EQ(sampled_csv.rfind("t,sample,x,y,theta\n", 0), 0u);
  const std::string log_csv = testing::ReadText(log);
  EXPECT_EQ(std::count(sampled_csv.begin(), sampled_csv.end(), '\n'),
            1 + 3 * (std::count(log_csv.begin(), log_csv.end(), '\n') - 1));

  // Over a changed model (same name, heavier) it is refused, naming the file.
  testing::WriteText(dir + "/heavier.yaml", "extends: " + omni4 + "\nchassis:\n  mass: 2.8\n");
  auto other = testing::RunTwinsim("replay --model " + dir + "/heavier.yaml --log " + log +
                                   " --backend learned --predictor " + dir + "/residual.pred --out " + dir + "/r.csv");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find(dir + "/residual.pred: residual predictor was trained over another version of model 'omni4'"),
            std::string::npos)
      << other.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/r.csv"));

  // Options of residual predictors without --residual, or out of range, are bad input.
  auto lone = testing::RunTwinsim("train --model " + omni4 + " --log " + log + " --nominal-engine ode --out " + dir +
                                  "/x.pred");
  EXPECT_EQ(lone.exit_code, 2);
  EXPECT_NE(lone.err.find("are for residual predictors only (add --residual)"), std::string::npos) << lone.err;
  auto steps = testing::RunTwinsim("train --model " + omni4 + " --log " + log +
                                   " --residual --nominal-substeps -3 --out " + dir + "/x.pred");
  EXPECT_EQ(steps.exit_code, 2);
  EXPECT_NE(steps.err.find("--nominal-substeps must be 1 to 1000"), std::string::npos) << steps.err;
  auto state = testing::RunTwinsim("train --model " + omni4 + " --log " + log +
                                   " --residual --nominal-state kalman --out " + dir + "/x.pred");
  EXPECT_EQ(state.exit_code, 2);
  EXPECT_NE(state.err.find("must be observer, tracker or auto, got 'kalman'"), std::string::npos) << state.err;
  auto lone_state = testing::RunTwinsim("train --model " + omni4 + " --log " + log + " --nominal-state observer --out " +
                                        dir + "/x.pred");
  EXPECT_EQ(lone_state.exit_code, 2);
  EXPECT_NE(lone_state.err.find("--nominal-state and --nominal-errors are for residual predictors only"),
            std::string::npos)
      << lone_state.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.pred"));
}

}  // namespace
}  // namespace twinsim

// `replay --samples` on a log with measurements prints how well the samples' distribution
// holds them; drawn on another engine than the model was fitted on, it warns where that
// engine's predictions leave the fitted engine's 90 % regions (issue 64). A robot with
// little grip (wheel friction 0.1) driven hard: the analytic engine, which does not
// simulate slip, is the one it was "fitted" on; ODE's wheels slip.
TEST(Cli, ReplaySamplesSayTheirCoverageAndAnEngineOffItsFit) {
  const std::string dir = testing::TempDir("replay_samples_coverage");
  ASSERT_EQ(testing::RunTwinsim("run " + testing::SourcePath("scenes/record_slipping_plant.yaml") + " --quiet --out " +
                                dir + "/plant")
                .exit_code,
            0);
  const std::string log = dir + "/plant/trajectory.csv";
  testing::WriteText(dir + "/low_grip.yaml", "extends: " + testing::SourcePath("models/omni4.yaml") +
                                                 "\nname: low_grip\nfitted_on: analytic\nwheels:\n  friction: 0.1\n");
  auto replay = [&](const std::string& backend) {
    return testing::RunTwinsim("replay --model " + dir + "/low_grip.yaml --log " + log +
                               " --samples 4 --horizon 8 --backend " + backend + " --out " + dir + "/" + backend + ".csv");
  };
  const auto analytic = replay("analytic");
  ASSERT_EQ(analytic.exit_code, 0) << analytic.err;
  EXPECT_NE(analytic.out.find("calibration of the samples' distribution"), std::string::npos) << analytic.out;
  EXPECT_NE(analytic.out.find("  8 frames (0.27 s)"), std::string::npos) << analytic.out;
  EXPECT_NE(analytic.out.find("by quarter of the log's turn rate"), std::string::npos) << analytic.out;
  EXPECT_EQ(analytic.err.find("warning: on"), std::string::npos) << analytic.err;
  const auto ode = replay("ode");
  ASSERT_EQ(ode.exit_code, 0) << ode.err;
  EXPECT_NE(ode.err.find("warning: on ode the predicted positions lie outside the analytic engine's 90 % region"),
            std::string::npos)
      << ode.err;
  // The default omni4 (no fitted_on): no engine to hold the samples against, no check.
  const auto plain = testing::RunTwinsim("replay --model " + testing::SourcePath("models/omni4.yaml") + " --log " + log +
                                         " --samples 4 --horizon 8 --backend ode --out " + dir + "/plain.csv");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.out.find("engine's 90 % region"), std::string::npos) << plain.out;
  EXPECT_EQ(plain.err.find("engine's 90 % region"), std::string::npos) << plain.err;
}

}  // namespace
}  // namespace twinsim
