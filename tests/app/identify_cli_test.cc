// `twinsim identify` and the arm part of `twinsim replay` through the binary.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "analysis/arm_replay.h"
#include "identification/synthetic_arm_data.h"
#include "io/csv_table.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::RunTwinsim;
using testing::SourcePath;

// The RRR arm with heavier links and more friction than models/rrr.yaml says.
ArmModel HeavierRrr() {
  ArmModel m = LoadArmModel(SourcePath("models/rrr.yaml"));
  for (auto& j : m.joints) {
    j.child.mass *= 1.15;
    j.child.com *= 1.1;
    j.viscous *= 1.3;
    j.coulomb *= 0.8;
  }
  return m;
}

std::string WriteLog(const std::string& dir, const std::string& name, int still_joint = -1, double seconds = 8) {
  const ArmModel truth = HeavierRrr();
  testing::SensorNoise noise;
  noise.counts_per_rev = 1 << 18;
  noise.torque_fraction = 0.01;
  const ArmLog log =
      testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 21), seconds, 500.0, noise, still_joint);
  WriteArmLog(dir + "/" + name, log, false);
  return dir + "/" + name;
}

TEST(IdentifyCli, IdentifiesWritesALoadableModelAndReplaysIt) {
  const std::string dir = testing::TempDir("identify_cli");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string out = dir + "/out/rrr_identified.yaml";
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + out +
                      " --cutoff 15 --report " + dir + "/report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("parameter"), std::string::npos);
  EXPECT_NE(r.out.find("a priori"), std::string::npos);
  EXPECT_NE(r.out.find("rel. std"), std::string::npos);
  EXPECT_NE(r.out.find("fc3"), std::string::npos);
  EXPECT_NE(r.out.find(out), std::string::npos);
  // The same inputs give the same bytes.
  const std::string again = dir + "/again.yaml";
  ASSERT_EQ(RunTwinsim("identify --quiet --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + again +
                       " --cutoff 15")
                .exit_code,
            0);
  std::string first = testing::ReadText(out), second = testing::ReadText(again);
  EXPECT_EQ(first.substr(first.find("robot:")), second.substr(second.find("robot:")));
  const ArmModel identified = LoadArmModel(out);
  EXPECT_EQ(identified.Validate(), "");
  EXPECT_EQ(identified.dof(), 3);
  EXPECT_NEAR(identified.joints[2].coulomb, 0.8 * 0.5, 0.02);
  EXPECT_NEAR(identified.joints[1].viscous, 1.3 * 0.3, 0.02);
  const std::string parameters = testing::ReadText(dir + "/report/parameters.csv");
  EXPECT_EQ(std::count(parameters.begin(), parameters.end(), '\n'), 22);  // header and 21 base parameters
  EXPECT_EQ(parameters.substr(0, parameters.find('\n')),
            "index,parameter,description,a_priori,identified,relative_std_pct,model");
  EXPECT_NE(parameters.find(",fc3,Coulomb friction of joint 3,0.5,"), std::string::npos) << parameters;
  EXPECT_EQ(ReadCsvTable(dir + "/report/joints.csv").rows.size(), 3u);
#ifdef TWINSIM_HAVE_OSMESA
  EXPECT_TRUE(std::filesystem::exists(dir + "/report/torque_joint3.png"));
#endif

  // Replay: one row of model torques per input row, close to the measured ones.
  const std::string torques = dir + "/tau.csv";
  auto replay = RunTwinsim("replay --model " + out + " --log " + log + " --out " + torques + " --cutoff 15");
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  const CsvTable t = ReadCsvTable(torques);
  const ArmLog measured = ReadArmLog(log);
  ASSERT_EQ(t.header, (std::vector<std::string>{"t", "tau1", "tau2", "tau3"}));
  ASSERT_EQ(static_cast<int>(t.rows.size()), measured.rows());
  for (int j = 0; j < 3; ++j) {
    double error = 0, rms = 0;
    for (int r = measured.edge_samples; r < measured.rows() - measured.edge_samples; ++r) {
      error += std::pow(t.rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(j + 1)] - measured.tau(r, j), 2);
      rms += std::pow(measured.tau(r, j), 2);
    }
    // The 1 % torque noise and little else.
    EXPECT_LT(std::sqrt(error / rms), 0.03) << "joint " << j + 1;
  }
}

TEST(IdentifyCli, TheCutoffIsChosenFromTheLogsByDefaultAndSaidWhere) {
  const std::string dir = testing::TempDir("identify_cutoff");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string model = SourcePath("models/rrr.yaml");
  auto chosen = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/auto.yaml");
  ASSERT_EQ(chosen.exit_code, 0) << chosen.err;
  // Every candidate from 10 Hz up in octaves to a quarter of the 500 Hz rate, scored.
  EXPECT_NE(chosen.out.find("(held-out torque error per candidate: 10 Hz "), std::string::npos) << chosen.out;
  EXPECT_NE(chosen.out.find(", 80 Hz "), std::string::npos) << chosen.out;
  const std::string comment = testing::ReadText(dir + "/auto.yaml");
  EXPECT_NE(comment.find(" Hz (auto); "), std::string::npos) << comment;
  // A number is used as given, and nothing is chosen.
  auto fixed = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/fixed.yaml --cutoff 15");
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  EXPECT_EQ(fixed.out.find("per candidate"), std::string::npos) << fixed.out;
  EXPECT_NE(testing::ReadText(dir + "/fixed.yaml").find("; derivatives at 15 Hz; "), std::string::npos);
}

TEST(IdentifyCli, PositionFrictionIsWrittenAsEffectsAndChosenFromTheLogsWithAuto) {
  // The synthetic RRR arm's friction is the same along the travel: three knots come out
  // near its constant levels, written as each joint's Coulomb friction (the lowest knot's)
  // and a position_friction effect with the rest; auto keeps one level.
  const std::string dir = testing::TempDir("identify_position_friction");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string model = SourcePath("models/rrr.yaml");
  auto three = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                          "/three.yaml --position-friction 3 --validate " + log);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  EXPECT_NE(three.out.find("Coulomb friction along each joint's travel"), std::string::npos) << three.out;
  const ArmModel truth = HeavierRrr(), written = LoadArmModel(dir + "/three.yaml");
  for (int j = 0; j < 3; ++j) {
    const JointEffects e = written.effects.joint(j);
    ASSERT_EQ(e.friction_profile.knots, 3) << "joint " << j + 1;
    EXPECT_EQ(*std::min_element(e.friction_profile.levels.begin(), e.friction_profile.levels.begin() + 3), 0) << "joint " << j + 1;
    for (int k = 0; k < 3; ++k) {
      const double level = written.joints[static_cast<std::size_t>(j)].coulomb + e.friction_profile.levels[static_cast<std::size_t>(k)];
      // 1 % torque noise on torques of several N·m: within 0.1 N·m of the true level.
      EXPECT_NEAR(level, truth.joints[static_cast<std::size_t>(j)].coulomb, 0.1) << "joint " << j + 1 << ", knot " << k + 1;
    }
  }
  auto automatic = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                              "/auto.yaml --position-friction auto");
  ASSERT_EQ(automatic.exit_code, 0) << automatic.err;
  EXPECT_NE(automatic.out.find("position friction: one level (held-out torque error per candidate: 0 "),
            std::string::npos)
      << automatic.out;
  EXPECT_NE(testing::ReadText(dir + "/auto.yaml").find("\n# position friction: one level"), std::string::npos);
  EXPECT_FALSE(LoadArmModel(dir + "/auto.yaml").effects.joint(0).position_friction());
  for (const char* bad : {"1", "13", "five", "-2"}) {
    auto r = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/bad.yaml --position-friction " +
                        bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.err.find("knots"), std::string::npos) << bad << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.yaml"));
}

TEST(IdentifyCli, PositionTorqueIsWrittenAsEffectsAndAutoKeepsNoneWhereTheArmHasNone) {
  // The synthetic RRR arm has no torque along its joints' travel beyond its gravity: three
  // knots beside the offsets come out near zero (the offset holds the first: p1 = 0), and
  // auto keeps none.
  const std::string dir = testing::TempDir("identify_position_torque");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string model = SourcePath("models/rrr.yaml");
  auto three = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                          "/three.yaml --offsets --position-torque 3 --validate " + log);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  EXPECT_NE(three.out.find("Torque along each joint's travel"), std::string::npos) << three.out;
  const ArmModel written = LoadArmModel(dir + "/three.yaml");
  for (int j = 0; j < 3; ++j) {
    const KnotProfile p = written.effects.joint(j).torque_profile;
    ASSERT_EQ(p.knots, 3) << "joint " << j + 1;
    EXPECT_EQ(p.levels[0], 0) << "joint " << j + 1 << ": the offset holds the first knot's level";
    // 1 % torque noise on torques of several N·m: measured, every level within 1.2 of its
    // standard errors (joint 2's, beside its gravity, about 0.11 N·m; the others' 0.004).
    for (int k = 1; k < 3; ++k) EXPECT_LT(std::abs(p.levels[static_cast<std::size_t>(k)]), 0.3) << "joint " << j + 1;
  }
  auto automatic = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                              "/auto.yaml --offsets --position-torque auto");
  ASSERT_EQ(automatic.exit_code, 0) << automatic.err;
  EXPECT_NE(automatic.out.find("position torque: none (held-out torque error per candidate: 0 "), std::string::npos)
      << automatic.out;
  EXPECT_FALSE(LoadArmModel(dir + "/auto.yaml").effects.joint(0).torque_profile.on());
  for (const char* bad : {"1", "13", "3.5"}) {
    auto r = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/bad.yaml --position-torque " +
                        bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.err.find("knots"), std::string::npos) << bad << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.yaml"));
}

TEST(IdentifyCli, OffsetsAndHeldOutValidation) {
  const std::string dir = testing::TempDir("identify_validate");
  const std::string log = WriteLog(dir, "run.csv");
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir +
                      "/m.yaml --offsets --validate " + log + " --report " + dir + "/report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("torque offsets (measured - model), written as torque_offset effects with tau0 = -offset:"),
            std::string::npos)
      << r.out;
  // The data has no offsets: the written effects are small (1 % torque noise).
  const ArmModel written = LoadArmModel(dir + "/m.yaml");
  EXPECT_EQ(ListArmEffects(written.effects).size(), 3u);
  for (int j = 0; j < 3; ++j) EXPECT_LT(std::abs(written.effects.joint(j).torque_offset), 0.1) << "joint " << j + 1;
  EXPECT_NE(r.out.find("held out: " + log), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("normalised (error / twice the effort limit)"), std::string::npos) << r.out;
  const std::string csv = testing::ReadText(dir + "/report/validation.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);  // header and 3 joints
}

TEST(IdentifyCli, OutputErrorRefinesTheEstimateAndSimulatesAllThreeModels) {
  const std::string dir = testing::TempDir("identify_output_error");
  const std::string log = WriteLog(dir, "run.csv");
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir +
                      "/m.yaml --output-error 0.1 --threads 2 --validate " + log + " --report " + dir + "/report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("output error: windows of 0.1 s simulated from the logged torques, 54 fitted and 18 held out"),
            std::string::npos)
      << r.out;
  // The fit's standard errors, a row per joint under the coordinates' headings.
  EXPECT_NE(r.out.find("standard errors (each window-long stretch of the logs an independent cluster; % of the value, "
                       "offsets in N·m or N):\njoint        scale k       viscous       Coulomb\n1 "),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("simulated from its torques: " + log), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("inverse dynamics beats holding on"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("identified beats holding on"), std::string::npos) << r.out;
  // The log is the inverse dynamics of its motion: the estimate simulates it about as well
  // as output error can (measured: the held-out windows' error 2 % worse, not kept); the
  // model file says which.
  const std::string yaml = testing::ReadText(dir + "/m.yaml");
  const bool kept = r.out.find("\nkept: the held-out windows are simulated better") != std::string::npos;
  EXPECT_NE(kept ? std::string::npos : r.out.find("not kept: the held-out windows are simulated no better"),
            std::string::npos)
      << r.out;
  EXPECT_NE(yaml.find(kept ? "refined by output error: windows of 0.1 s" : "output error on windows of 0.1 s tried and not kept"),
            std::string::npos)
      << yaml;
  // Three models, three horizons (0.1 s, 1 s, the free run), three joints, and the header.
  const std::string csv = testing::ReadText(dir + "/report/simulation.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 3 * 3 * 3) << csv;
  EXPECT_NE(csv.find("," + std::string("inverse dynamics") + ",0.1,1,"), std::string::npos) << csv;
  // The fit's coordinates with their standard errors: scale, viscous and Coulomb per joint.
  const std::string fitted = testing::ReadText(dir + "/report/output_error.csv");
  EXPECT_EQ(fitted.substr(0, fitted.find('\n')), "stage,joint,coordinate,value,standard_error");
  EXPECT_EQ(std::count(fitted.begin(), fitted.end(), '\n'), 1 + 3 * 3) << fitted;
  EXPECT_NE(fitted.find("\n1,3,coulomb,"), std::string::npos) << fitted;

  // A continuation: windows of 0.1 s, then of 0.2 s from where they ended, each stage
  // reported and named in the model file.
  auto two = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir +
                        "/two.yaml --output-error 0.1,0.2 --threads 2");
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_NE(two.out.find("stage 1 of 2 of the continuation\noutput error: windows of 0.1 s"), std::string::npos)
      << two.out;
  EXPECT_NE(two.out.find("stage 2 of 2 of the continuation\noutput error: windows of 0.2 s"), std::string::npos)
      << two.out;
  const std::string two_yaml = testing::ReadText(dir + "/two.yaml");
  EXPECT_NE(two_yaml.find("output error as a continuation, each stage from where the last ended:"), std::string::npos)
      << two_yaml;
  EXPECT_NE(two_yaml.find("windows of 0.2 s"), std::string::npos) << two_yaml;
  // Its first stage is the single refinement above.
  EXPECT_NE(two_yaml.find(kept ? "refined by output error: windows of 0.1 s"
                               : "output error on windows of 0.1 s tried and not kept"),
            std::string::npos)
      << two_yaml;

  // Windows of two lengths at once: one stage, both named in its report and model file.
  auto both = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir +
                         "/both.yaml --output-error 0.1+0.2 --threads 2");
  ASSERT_EQ(both.exit_code, 0) << both.err;
  EXPECT_NE(both.out.find("output error: windows of 0.1 s simulated from the logged torques, 54 fitted and 18 held out; "),
            std::string::npos)
      << both.out;
  EXPECT_NE(both.out.find("\n  windows of 0.1 and 0.2 s fitted at once (each length's squared errors"), std::string::npos)
      << both.out;
  EXPECT_EQ(both.out.find("stage 1 of"), std::string::npos) << both.out;
  const std::string both_yaml = testing::ReadText(dir + "/both.yaml");
  EXPECT_NE(both_yaml.find("windows of 0.1 and 0.2 s"), std::string::npos) << both_yaml;

  auto negative = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir +
                             "/n.yaml --output-error -1");
  EXPECT_EQ(negative.exit_code, 2);
  EXPECT_NE(negative.err.find("--output-error: the output-error horizon must be a positive number of seconds"),
            std::string::npos)
      << negative.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/n.yaml"));
}

// --output-error run: the whole runs' simulation error by multiple shooting, the last
// quarter of the log held out, the same model on one thread and two (deep-only: 16 s).
TEST(IdentifyCli, OutputErrorOverWholeRunsTheSameOnOneThreadAndTwo) {
  const std::string dir = testing::TempDir("identify_output_error_run");
  const std::string log = WriteLog(dir, "run.csv", -1, 4);
  const std::string base = "identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir;
  auto r = RunTwinsim(base + "/m.yaml --output-error run --segment 1 --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("output error over whole runs: each log's first three quarters fitted by multiple shooting (2 "
                       "segments of 1 s"),
            std::string::npos)
      << r.out;
  const bool kept = r.out.find("\nkept: the held-out quarters are simulated better") != std::string::npos;
  const std::string yaml = testing::ReadText(dir + "/m.yaml");
  EXPECT_NE(yaml.find(kept ? "refined by output error over whole runs: multiple shooting, segments of 1 s"
                           : "output error over whole runs (segments of 1 s) tried and not kept"),
            std::string::npos)
      << yaml;
  // Each segment's columns are simulated on their own.
  auto one = RunTwinsim(base + "/one.yaml --output-error run --segment 1 --threads 1");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(testing::ReadText(dir + "/one.yaml"), yaml);
  // The fit's printout with its standard errors, the same too.
  const auto fit_table = [](const std::string& out) {
    const std::size_t from = out.find("output error over whole runs"), to = out.find("kept: the held-out", from);
    return from == std::string::npos || to == std::string::npos ? std::string() : out.substr(from, to - from);
  };
  EXPECT_NE(fit_table(r.out).find("standard errors (each shooting segment an independent cluster"), std::string::npos)
      << r.out;
  EXPECT_EQ(fit_table(one.out), fit_table(r.out));
}

// The words that are no horizon, refused before anything runs.
TEST(IdentifyCli, OutputErrorOverWholeRunsRefusesWhatIsNoHorizon) {
  const std::string dir = testing::TempDir("identify_output_error_refused");
  const std::string log = WriteLog(dir, "run.csv", -1, 4);
  const std::string base = "identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir;
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"--output-error runs", "--output-error runs: give the windows' length in seconds (0.1, or 0.1+1 for both "
                                   "at once), or run for whole runs"},
           {"--output-error 0.1+", "--output-error 0.1+: give the windows' length in seconds"},
           {"--output-error 0.1+0", "--output-error 0.1+0: each length fitted at once must be above 0 s"},
           {"--output-error 0+1", "--output-error 0+1: each length fitted at once must be above 0 s"},
           {"--output-error run+1", "--output-error run+1: give the windows' length in seconds"},
           {"--output-error 0.1s", "--output-error 0.1s: give the windows' length in seconds"},
           {"--output-error 0.1,,1", "--output-error : give the windows' length in seconds"},
           {"--output-error 0.1,0", "--output-error 0.1,0: 0 (none) cannot be a stage of a continuation"},
           {"--output-error 0.1,-1", "the output-error horizon must be a positive number of seconds"},
           {"--segment 2", "--segment cuts --output-error run's whole runs: give --output-error run as well"},
           {"--output-error run --segment 0", "the shooting segments must be a positive number of seconds"},
           {"--output-error run --segment 1.5", "too short for the whole-run output-error fit"}}) {
    SCOPED_TRACE(args);
    auto bad = RunTwinsim(base + "/bad.yaml " + args);
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find(message), std::string::npos) << bad.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/bad.yaml"));
  }
}

TEST(IdentifyCli, ReplayOfTheUrdfWritesTheModelsTorques) {
  const std::string dir = testing::TempDir("replay_arm_cli");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string out = dir + "/tau.csv";
  auto r = RunTwinsim("replay --quiet --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ArmModel model = LoadArmModel(SourcePath("models/rrr.yaml"));
  const ArmLog measured = ReadArmLog(log);
  // The model's commands: its rigid torques sent one sample (delay_samples) ahead.
  const Eigen::MatrixXd expected = PredictArmCommands(model, measured);
  const CsvTable t = ReadCsvTable(out);
  ASSERT_EQ(static_cast<int>(t.rows.size()), measured.rows());
  for (int row : {0, 100, measured.rows() - 1})
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(t.rows[static_cast<std::size_t>(row)][static_cast<std::size_t>(j + 1)], expected(row, j), 1e-9);
}

TEST(IdentifyCli, JointCountMismatchIsExitTwoNamingBothCounts) {
  const std::string dir = testing::TempDir("identify_mismatch");
  const std::string log = testing::WriteText(dir + "/two.csv", "t,q1,q2,tau1,tau2\n0,0,0,0,0\n0.01,0,0,0,0\n0.02,0,0,0,0\n");
  const std::string model = SourcePath("models/rrr.yaml");
  auto r = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/m.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(log + ":1: the log has 2 joints (q1..q2, tau1..tau2) but the model 'rrr' (" + model + ") has 3"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
  auto replay = RunTwinsim("replay --model " + model + " --log " + log + " --out " + dir + "/t.csv");
  EXPECT_EQ(replay.exit_code, 2);
  EXPECT_NE(replay.err.find("the log has 2 joints"), std::string::npos) << replay.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/t.csv"));
}

TEST(IdentifyCli, AJointThatNeverMovesIsExitTwoNamingTheParameter) {
  const std::string dir = testing::TempDir("identify_still");
  const std::string log = WriteLog(dir, "still.csv", 2);
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir + "/m.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(log + ": the data does not excite base parameters"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fc3 (Coulomb friction of joint 3: it never moves)"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
}

TEST(IdentifyCli, PoorlyExcitedDataIsExitTwoSayingHowToMove) {
  // Every joint moves, but along one slow sine for a second: too little to tell the
  // parameters apart. That is bad input (exit 2), not an internal error (3).
  const std::string dir = testing::TempDir("identify_poor");
  const ArmModel truth = HeavierRrr();
  const std::string log = dir + "/poor.csv";
  WriteArmLog(log, testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 21, 1, 0.05), 1.0, 500.0, {}),
              false);
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir + "/m.yaml");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(log + ": the data does not excite base parameter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Move every joint in both directions with varied speeds and accelerations"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
}

TEST(IdentifyCli, TorquesNoRealArmFitsAreExitTwo) {
  // Torques in absurd units: even the physically consistent fit is no valid arm. That is
  // the data's fault (exit 2), not an internal error (3).
  const std::string dir = testing::TempDir("identify_units");
  const ArmModel truth = HeavierRrr();
  ArmLog absurd = testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 21), 8.0, 500.0, {});
  absurd.tau *= 1e150;
  const std::string log = dir + "/absurd.csv";
  WriteArmLog(log, absurd, false);
  auto r = RunTwinsim("identify --model " + SourcePath("models/rrr.yaml") + " --log " + log + " --out " + dir + "/m.yaml");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // The reader refuses torques no joint produces, before any fit (the fit's own refusal
  // of such data is tested in wls_identification_test.cc).
  EXPECT_NE(r.err.find(log + ":2: column 'tau1': "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is beyond what a joint reports"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
}

TEST(IdentifyCli, BadOptionsAreExitTwo) {
  const std::string dir = testing::TempDir("identify_options");
  const std::string log = WriteLog(dir, "run.csv");
  const std::string model = SourcePath("models/rrr.yaml");
  auto urdf = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/m.urdf");
  EXPECT_EQ(urdf.exit_code, 2);
  EXPECT_NE(urdf.err.find("give a .yaml or .yml path"), std::string::npos) << urdf.err;
  auto decimate = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/m.yaml --decimate 0");
  EXPECT_EQ(decimate.exit_code, 2);
  EXPECT_NE(decimate.err.find("decimate must be at least 1"), std::string::npos) << decimate.err;
  auto cutoff = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir + "/m.yaml --cutoff 0");
  EXPECT_EQ(cutoff.exit_code, 2);
  auto omni = RunTwinsim("identify --model " + SourcePath("models/omni4.yaml") + " --log " + log + " --out " + dir +
                         "/m.yaml");
  EXPECT_EQ(omni.exit_code, 2);
  // An omni model is identified from an omni log: the arm log lacks its columns.
  EXPECT_NE(omni.err.find("run.csv:1: missing column 'x'"), std::string::npos) << omni.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
  auto arm_safeguard = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                                  "/m.yaml --safeguard logs");
  EXPECT_EQ(arm_safeguard.exit_code, 2);
  EXPECT_NE(arm_safeguard.err.find("--safeguard is for omni robots"), std::string::npos) << arm_safeguard.err;
  auto arm_harmonics = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                                  "/m.yaml --no-turn-harmonics");
  EXPECT_EQ(arm_harmonics.exit_code, 2);
  EXPECT_NE(arm_harmonics.err.find("--no-turn-harmonics is for omni robots"), std::string::npos) << arm_harmonics.err;
  // Pre-sliding is fitted by output error, as one of two models.
  auto presliding_alone = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                                     "/m.yaml --presliding maxwell");
  EXPECT_EQ(presliding_alone.exit_code, 2);
  EXPECT_NE(presliding_alone.err.find("--presliding refines by output error"), std::string::npos)
      << presliding_alone.err;
  auto presliding_word = RunTwinsim("identify --model " + model + " --log " + log + " --out " + dir +
                                    "/m.yaml --output-error 0.1 --presliding dahl");
  EXPECT_EQ(presliding_word.exit_code, 2);
  EXPECT_NE(presliding_word.err.find("--presliding"), std::string::npos) << presliding_word.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.yaml"));
  // The intervals' safeguard on left-out logs needs a second log to leave one out.
  const std::string omni_log = dir + "/omni.csv";
  {
    std::ofstream f(omni_log);
    f << "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n";
    for (int i = 0; i < 300; ++i) f << i / 30.0 << "," << 0.01 * i << ",0,0,0.3,0,0\n";
  }
  const std::string omni_base =
      "identify --model " + SourcePath("models/omni4.yaml") + " --log " + omni_log + " --out " + dir + "/o";
  auto one_log = RunTwinsim(omni_base + " --safeguard logs");
  EXPECT_EQ(one_log.exit_code, 2);
  EXPECT_NE(one_log.err.find("--safeguard logs needs at least two logs"), std::string::npos) << one_log.err;
  auto bad_word = RunTwinsim(omni_base + " --safeguard always");
  EXPECT_EQ(bad_word.exit_code, 2);
  EXPECT_NE(bad_word.err.find("--safeguard"), std::string::npos) << bad_word.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/o"));
}

}  // namespace
}  // namespace twinsim
