// `twinsim run` on arm scenes through the binary: the log, the plots, the summary, and
// bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "control/computed_torque.h"
#include "io/csv_table.h"
#include "robots/arm/arm_log.h"
#include "scene/arm_scene.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::RunTwinsim;
using testing::SourcePath;

// A short writing scene: the letter T on the rod-tip arm controlled with the bare model.
std::string ShortScene(const std::string& dir, const std::string& extra = "") {
  return testing::WriteText(dir + "/t.yaml",
                            "name: short\n"
                            "robot: arm\n"
                            "model: " + SourcePath("models/rrr_rod_tip.yaml") + "\n"
                            "task: {type: writing, letters: T}\n"
                            "controller: {type: pd_feedforward, model: " + SourcePath("models/rrr.yaml") + ", bandwidth: 8}\n"
                            "plots:\n"
                            "  - {type: tool_path, file: path.png}\n"
                            "  - {type: joint_torques, file: torque.png}\n"
                            "  - {type: tracking_error, file: error.png}\n" + extra);
}

TEST(RunArmCli, WritesTheArmLogTrackingCsvAndPlots) {
  const std::string dir = testing::TempDir("run_arm_cli");
  const std::string scene = ShortScene(dir);
  auto r = RunTwinsim("run " + scene + " --out " + dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scene short: arm rrr_rod_tip with pd_feedforward (model rrr) on analytic"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("max error [mrad]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(dir + "/out/trajectory.csv"), std::string::npos) << r.out;

  // The contract's arm log with qd and qref; the arm log reader reads it back.
  const CsvTable table = ReadCsvTable(dir + "/out/trajectory.csv");
  EXPECT_EQ(table.header, (std::vector<std::string>{"t", "q1", "q2", "q3", "tau1", "tau2", "tau3", "qd1", "qd2", "qd3",
                                                     "qref1", "qref2", "qref3"}));
  const ArmLog log = ReadArmLog(dir + "/out/trajectory.csv");
  EXPECT_EQ(log.dof, 3);
  EXPECT_TRUE(log.qd_logged);
  EXPECT_EQ(log.qref.rows(), log.rows());

  // The same trial through the library: the same numbers (to the CSV's digits).
  const ArmScene s = LoadArmScene(scene);
  const TrackingTrial trial = RunTrackingTrial(s.plant, s.hat, ArmSceneReference(s), s.tracking);
  ASSERT_EQ(log.rows(), trial.t.size());
  const Eigen::MatrixXd error = log.qref - log.q;
  for (int j = 0; j < 3; ++j) {
    // The CSV keeps 10 significant digits.
    EXPECT_NEAR(error.col(j).cwiseAbs().maxCoeff(), trial.error_max[j], 1e-9) << "joint " << j + 1;
    EXPECT_NEAR((log.tau.col(j) - trial.command.col(j)).cwiseAbs().maxCoeff(), 0, 1e-8);
  }
  // The bare model on the rod-tip arm misses by millimetres (docs/writing_task.md).
  EXPECT_GT(trial.error_max.maxCoeff(), 1e-3);

  const CsvTable tracking = ReadCsvTable(dir + "/out/tracking.csv");
  EXPECT_EQ(tracking.header.size(), 16u);
  EXPECT_EQ(tracking.header[4], "demand1");

  // Same scene, same bytes.
  ASSERT_EQ(RunTwinsim("run --quiet " + scene + " --out " + dir + "/again").exit_code, 0);
  EXPECT_EQ(testing::ReadText(dir + "/out/trajectory.csv"), testing::ReadText(dir + "/again/trajectory.csv"));
}

TEST(RunArmCli, DrawsThePlots) {
  SKIP_WITHOUT_OSMESA();
  const std::string dir = testing::TempDir("run_arm_cli_plots");
  auto r = RunTwinsim("run --quiet " + ShortScene(dir) + " --out " + dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* png : {"path.png", "torque_joint1.png", "torque_joint2.png", "torque_joint3.png", "error.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + png)) << png;
    EXPECT_GT(std::filesystem::file_size(dir + "/out/" + png), 5000u) << png;
  }
}

TEST(RunArmCli, BadSceneKeysAndTheLearnedBackendAreExitTwo) {
  const std::string dir = testing::TempDir("run_arm_cli_bad");
  const std::string bad = testing::WriteText(dir + "/bad.yaml",
                                             "name: bad\n"
                                             "robot: arm\n"
                                             "model: " + SourcePath("models/rrr.yaml") + "\n"
                                             "task: {type: writing, speeed: 1}\n");
  auto r = RunTwinsim("run " + bad + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ":4:23: unknown key 'speeed' in 'task'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trajectory.csv"));

  auto learned = RunTwinsim("run " + ShortScene(dir) + " --backend learned --out " + dir + "/out");
  EXPECT_EQ(learned.exit_code, 2);
  EXPECT_NE(learned.err.find("--backend learned needs --predictor P"), std::string::npos) << learned.err;
  auto unknown = RunTwinsim("run " + ShortScene(dir) + " --backend mujoco --out " + dir + "/out");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trajectory.csv"));

  const std::string kind = testing::WriteText(dir + "/kind.yaml", "name: k\nrobot: boat\n");
  auto boat = RunTwinsim("run " + kind);
  EXPECT_EQ(boat.exit_code, 2);
  EXPECT_NE(boat.err.find(kind + ":2:8: 'robot': expected arm"), std::string::npos) << boat.err;
}

// The user's path to a learned arm: record seeded random motion of the plant with an
// arm scene, train on the logs, and run a scene on the learned backend. The learned
// arm must track the letter about as the plant does (the controller is the same), and
// a predictor trained for another model is refused.
TEST(RunArmCli, RecordsTrainsAndRunsTheLearnedBackend) {
  const std::string dir = testing::TempDir("run_arm_cli_learned");
  std::string record = testing::ReadText(SourcePath("scenes/rrr_record_plant.yaml"));
  const std::string from = "duration: 20", to = "duration: 20";
  ASSERT_NE(record.find(from), std::string::npos);
  record.replace(record.find(from), from.size(), to);
  for (const std::string rel : {"../models/rrr_plant.yaml", "../models/rrr.yaml"}) {
    ASSERT_NE(record.find(rel), std::string::npos) << rel;
    record.replace(record.find(rel), rel.size(), SourcePath("models/" + rel.substr(10)));
  }
  const std::string record_scene = testing::WriteText(dir + "/record.yaml", record);
  std::string logs;
  for (int seed = 1; seed <= 4; ++seed) {
    const std::string out = dir + "/rec" + std::to_string(seed);
    auto r = RunTwinsim("run --quiet " + record_scene + " --seed " + std::to_string(seed) + " --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    logs += " --log " + out + "/trajectory.csv";
  }
  // Different seeds, different motion.
  EXPECT_NE(testing::ReadText(dir + "/rec1/trajectory.csv"), testing::ReadText(dir + "/rec2/trajectory.csv"));
  auto train = RunTwinsim("train --quiet --model " + SourcePath("models/rrr.yaml") + logs +
                          " --kind linear --horizon 1 --out " + dir + "/rrr.pred");
  ASSERT_EQ(train.exit_code, 0) << train.err;
  auto residual = RunTwinsim("train --quiet --model " + SourcePath("models/rrr.yaml") + logs +
                             " --kind linear --residual --out " + dir + "/rrr_residual.pred");
  ASSERT_EQ(residual.exit_code, 0) << residual.err;

  // The letter T with the nominal model's computed torque, on the plant and on the
  // learned backend (the scene names the nominal model, which the predictor was
  // trained for).
  auto scene = [&](const std::string& model) {
    return testing::WriteText(dir + "/" + model + ".yaml",
                              "name: t_" + model + "\nrobot: arm\nmodel: " + SourcePath("models/" + model + ".yaml") +
                                  "\ntask: {type: writing, letters: T}\n"
                                  "controller: {type: computed_torque, model: " + SourcePath("models/rrr.yaml") + "}\n");
  };
  ASSERT_EQ(RunTwinsim("run --quiet " + scene("rrr_plant") + " --out " + dir + "/plant").exit_code, 0);
  auto learned = RunTwinsim("run --quiet " + scene("rrr") + " --backend learned --predictor " + dir +
                            "/rrr.pred --out " + dir + "/learned");
  ASSERT_EQ(learned.exit_code, 0) << learned.err;
  const ArmLog plant = ReadArmLog(dir + "/plant/trajectory.csv");
  const ArmLog run = ReadArmLog(dir + "/learned/trajectory.csv");
  ASSERT_EQ(plant.rows(), run.rows());
  const Eigen::MatrixXd plant_error = plant.qref - plant.q, learned_error = run.qref - run.q;
  for (int j = 0; j < 3; ++j) {
    const double p = plant_error.col(j).cwiseAbs().maxCoeff(), l = learned_error.col(j).cwiseAbs().maxCoeff();
    std::printf("[measured] joint %d: max tracking error plant %.2f mrad, learned %.2f mrad, |q diff| %.2f mrad\n",
                j + 1, 1e3 * p, 1e3 * l, 1e3 * (plant.q.col(j) - run.q.col(j)).cwiseAbs().maxCoeff());
    // The plant misses by up to 12 mrad (elbow friction and payload); the learned arm
    // must miss by the same order, not by the nominal model's 0.07 mrad nor diverge.
    EXPECT_LT((plant.q.col(j) - run.q.col(j)).cwiseAbs().maxCoeff(), 0.03) << "joint " << j + 1;
  }
  EXPECT_GT(learned_error.col(2).cwiseAbs().maxCoeff(), 2e-3);

  // The residual model (the nominal model's step plus a learned correction) is closer
  // to the plant than the nominal model alone, on every joint.
  ASSERT_EQ(RunTwinsim("run --quiet " + scene("rrr") + " --out " + dir + "/nominal").exit_code, 0);
  ASSERT_EQ(RunTwinsim("run --quiet " + scene("rrr") + " --backend learned --predictor " + dir +
                       "/rrr_residual.pred --out " + dir + "/residual")
                .exit_code,
            0);
  const ArmLog nominal = ReadArmLog(dir + "/nominal/trajectory.csv");
  const ArmLog hybrid = ReadArmLog(dir + "/residual/trajectory.csv");
  for (int j = 0; j < 3; ++j) {
    const auto rms = [&](const ArmLog& log) {
      return std::sqrt((plant.q.col(j) - log.q.col(j)).squaredNorm() / static_cast<double>(plant.rows()));
    };
    std::printf("[measured] joint %d: q RMS vs the plant: nominal %.3f mrad, residual %.3f mrad, learned %.3f mrad\n",
                j + 1, 1e3 * rms(nominal), 1e3 * rms(hybrid), 1e3 * rms(run));
    EXPECT_LT(rms(hybrid), 0.9 * rms(nominal)) << "joint " << j + 1;
  }

  // A predictor trained for rrr is refused for a scene whose model is rrr_rod.
  auto other = RunTwinsim("run --quiet " + scene("rrr_rod") + " --backend learned --predictor " + dir +
                          "/rrr.pred --out " + dir + "/other");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("trained for"), std::string::npos) << other.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/other/trajectory.csv"));
}

}  // namespace
}  // namespace twinsim
