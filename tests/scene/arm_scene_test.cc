// Arm scenes: the shipped ones load, references of each task type, bad input, and the
// `sensors:` block that makes trajectory.csv look like a real arm's log.
#include "scene/arm_scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/csv_table.h"
#include "robots/arm/arm_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

std::string ArmSceneErrorOf(const std::string& yaml) {
  try {
    LoadArmSceneFromString(yaml, "a.yaml", SourcePath("scenes"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ArmScene, ShippedScenesLoadAndAreArmScenes) {
  const ArmScene bare = LoadArmScene(SourcePath("scenes/rrr_writing.yaml"));
  EXPECT_EQ(SceneRobotKind(SourcePath("scenes/rrr_writing.yaml")), RobotKind::kArm);
  EXPECT_EQ(bare.name, "rrr_writing");
  EXPECT_EQ(bare.plant.name, "rrr");
  EXPECT_EQ(bare.hat.name, "rrr");
  EXPECT_EQ(bare.task.type, "writing");
  EXPECT_EQ(bare.task.writing.letters, "TUE");
  EXPECT_EQ(bare.plots.size(), 3u);
  const ArmScene tip = LoadArmScene(SourcePath("scenes/rrr_writing_rod_tip.yaml"));
  EXPECT_EQ(tip.plant.name, "rrr_rod_tip");
  EXPECT_EQ(tip.hat.name, "rrr");
  EXPECT_EQ(tip.tracking.controller, TrackingController::kComputedTorque);
  EXPECT_EQ(SceneRobotKind(SourcePath("scenes/drive45.yaml")), RobotKind::kOmni);
}

TEST(ArmScene, TaskReferencesInClosedForm) {
  const std::string head = "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n";
  // A sinusoid: exact derivatives.
  ArmScene s = LoadArmSceneFromString(
      head + "task: {type: sinusoid, q: [0, 0.8, -1.5], amplitude: [0.2, 0.1, 0], frequency: 2, duration: 0.5}\n",
      "a.yaml", SourcePath("scenes"));
  ArmReference ref = ArmSceneReference(s);
  ASSERT_EQ(ref.t.size(), 501);
  const double w = 4 * kPi, t = ref.t[123];
  EXPECT_NEAR(ref.q(123, 0), 0.2 * std::sin(w * t), 1e-15);
  EXPECT_NEAR(ref.qd(123, 1), 0.1 * w * std::cos(w * t), 1e-13);
  EXPECT_NEAR(ref.qdd(123, 0), -0.2 * w * w * std::sin(w * t), 1e-12);
  EXPECT_EQ(ref.q(400, 2), -1.5);
  // A step at 0.1 s; the controller's model defaults to the plant.
  s = LoadArmSceneFromString(head + "task: {type: step, q: [0, 0.8, -1.5], to: [0.1, 0.9, -1.4], at: 0.1, duration: 0.3}\n",
                             "a.yaml", SourcePath("scenes"));
  ref = ArmSceneReference(s);
  EXPECT_EQ(ref.q(99, 0), 0);
  EXPECT_EQ(ref.q(100, 0), 0.1);
  EXPECT_EQ(ref.qd.cwiseAbs().maxCoeff(), 0);
  EXPECT_EQ(s.hat_path, s.plant_path);
  // The writing task: the reference of WritingTaskReference with the scene's options.
  s = LoadArmSceneFromString(head + "task: {type: writing, letters: T, speed: 0.5}\n", "a.yaml", SourcePath("scenes"));
  WritingTaskOptions w_options;
  w_options.letters = "T";
  w_options.speed = 0.5;
  const ArmReference direct = WritingTaskReference(s.hat, w_options);
  ref = ArmSceneReference(s);
  ASSERT_EQ(ref.q.rows(), direct.q.rows());
  EXPECT_EQ((ref.q - direct.q).cwiseAbs().maxCoeff(), 0);
}

TEST(ArmScene, BadInputIsReportedWithFileLineAndColumn) {
  const std::string e = ArmSceneErrorOf(
      "name: a\n"
      "robot: arm\n"
      "model: ../models/rrr.yaml\n"
      "task: {type: writing, leters: T}\n"
      "controller: {type: computed_torque, bandwith: 10, damping: -1}\n"
      "plots: [{type: torque, file: t.png}, {type: tool_path, file: a/b.png}]\n");
  EXPECT_NE(e.find("a.yaml:4:23: unknown key 'leters' in 'task'"), std::string::npos) << e;
  EXPECT_NE(e.find("a.yaml:5:37: unknown key 'bandwith' in 'controller'"), std::string::npos) << e;
  EXPECT_NE(e.find("a.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("'damping'"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown value 'torque' (known: tool_path, joint_torques, tracking_error)"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a plain file name ending in .png"), std::string::npos) << e;

  const std::string sizes = ArmSceneErrorOf(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n"
      "task: {type: hold, q: [0, 0.8], duration: 1}\n");
  EXPECT_NE(sizes.find("a.yaml:4:"), std::string::npos) << sizes;
  EXPECT_NE(sizes.find("'q'"), std::string::npos) << sizes;

  const std::string limits = ArmSceneErrorOf(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n"
      "task: {type: hold, q: [0, 0.8, 9], duration: 1}\n");
  EXPECT_NE(limits.find("joint 3 ('elbow') at 9"), std::string::npos) << limits;

  const std::string missing = ArmSceneErrorOf("name: a\nrobot: arm\n");
  EXPECT_NE(missing.find("missing required key 'model'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing required key 'task'"), std::string::npos) << missing;

  const std::string hat = ArmSceneErrorOf(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\ncontroller: {model: ../models/nope.yaml}\ntask: {type: writing}\n");
  EXPECT_NE(hat.find("nope.yaml"), std::string::npos) << hat;

  // Out of reach: refused when the reference is built, naming the scene.
  const ArmScene far = LoadArmSceneFromString(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\ntask: {type: writing, plane_x: 2}\n", "a.yaml",
      SourcePath("scenes"));
  try {
    ArmSceneReference(far);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.yaml: the writing task cannot be drawn by 'rrr'"), std::string::npos)
        << e.what();
  }
}

// An arm scene on the bare RRR arm (its exact model) with `task` and `extra` keys.
std::string SensorScene(const std::string& task, const std::string& extra) {
  return "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\nseed: 7\ntask: " + task + "\n" + extra;
}

ArmScene LoadSensorScene(const std::string& task, const std::string& extra) {
  return LoadArmSceneFromString(SensorScene(task, extra), "a.yaml", SourcePath("scenes"));
}

TrackingTrial RunScene(const ArmScene& s) {
  return RunTrackingTrial(s.plant, s.hat, ArmSceneReference(s), s.tracking);
}

const char kSine[] = "{type: sinusoid, q: [0, 0.6, -1.2], amplitude: [0.4, 0.3, 0.5], frequency: 0.5, duration: 4}";

TEST(ArmSceneSensors, AbsentBlockGivesTheExactLogByteForByte) {
  const ArmScene s = LoadSensorScene(kSine, "");
  EXPECT_TRUE(s.sensors.IsIdeal());
  const TrackingTrial trial = RunScene(s);
  // The log `twinsim run` wrote before the sensors existed.
  const std::string before =
      JointColumnsCsv(trial.t, {"q", "tau", "qd", "qref"}, {&trial.q, &trial.command, &trial.qd, &trial.q_ref});
  EXPECT_EQ(ArmSceneTrajectoryCsv(s, trial), before);
  // An explicitly ideal block is the same.
  const ArmScene zeros = LoadSensorScene(
      kSine, "sensors: {encoder_counts_per_rev: 0, torque_noise: [0, 0, 0], log_velocities: true}\n");
  EXPECT_TRUE(zeros.sensors.IsIdeal());
  EXPECT_EQ(ArmSceneTrajectoryCsv(zeros, trial), before);
}

TEST(ArmSceneSensors, EncoderCountsRoundPositionsToWholeCounts) {
  const ArmScene s = LoadSensorScene(kSine, "sensors:\n  encoder_counts_per_rev: [40000, 4096, 0]\n");
  const TrackingTrial trial = RunScene(s);
  const ArmLog log = SensedArmLog(s.sensors, trial, s.seed);
  const double steps[] = {2 * kPi / 40000, 2 * kPi / 4096};  // rad per count
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(s.sensors.count_step[j], steps[j], 1e-18);
    double worst = 0;  // counts off a whole number
    for (int k = 0; k < log.rows(); ++k) {
      const double counts = log.q(k, j) / steps[j];
      worst = std::max(worst, std::abs(counts - std::round(counts)));
      ASSERT_LE(std::abs(log.q(k, j) - trial.q(k, j)), 0.5 * steps[j] * (1 + 1e-9)) << "row " << k;
    }
    EXPECT_LE(worst, 1e-12) << "joint " << j + 1;
    // Quantised: far fewer distinct values than samples, and not the exact positions.
    EXPECT_GT((log.q.col(j) - trial.q.col(j)).cwiseAbs().maxCoeff(), 0.1 * steps[j]);
  }
  EXPECT_EQ(log.q.col(2), trial.q.col(2));  // 0 counts: exact
  // Torques, velocities and the reference are untouched.
  EXPECT_EQ(log.tau, trial.command);
  EXPECT_EQ(log.qd, trial.qd);
  EXPECT_EQ(log.qref, trial.q_ref);

  // In the file (9 decimals) every position still reads back as a whole count.
  const ArmLog back = ParseArmLog(ArmSceneTrajectoryCsv(s, trial), "trajectory.csv");
  for (int j = 0; j < 2; ++j) {
    for (int k = 0; k < back.rows(); ++k) {
      const double counts = std::round(log.q(k, j) / steps[j]);
      ASSERT_EQ(std::round(back.q(k, j) / steps[j]), counts) << "row " << k;
      ASSERT_LE(std::abs(back.q(k, j) - counts * steps[j]), 5.1e-10) << "row " << k;
    }
  }

  // One number applies to every (revolute) joint.
  const ArmScene all = LoadSensorScene(kSine, "sensors: {encoder_counts_per_rev: 4096}\n");
  ASSERT_EQ(all.sensors.count_step.size(), 3);
  EXPECT_EQ(all.sensors.count_step, Eigen::Vector3d::Constant(2 * kPi / 4096));
}

TEST(ArmSceneSensors, TorqueNoiseHasTheGivenSigmaAndComesFromTheSeed) {
  const std::string hold = "{type: hold, q: [0, 0.6, -1.2], duration: 10}";  // 10001 samples
  const ArmScene s = LoadSensorScene(hold, "sensors: {torque_noise: [0.02, 0.5, 0]}\n");
  const TrackingTrial trial = RunScene(s);
  const ArmLog log = SensedArmLog(s.sensors, trial, s.seed);
  const Eigen::MatrixXd noise = log.tau - trial.command;  // N·m
  const double n = static_cast<double>(noise.rows());
  const double sigmas[] = {0.02, 0.5};
  for (int j = 0; j < 2; ++j) {
    const double mean = noise.col(j).mean();
    const double std = std::sqrt((noise.col(j).array() - mean).square().sum() / (n - 1));
    EXPECT_NEAR(std, sigmas[j], 0.1 * sigmas[j]) << "joint " << j + 1;
    EXPECT_LT(std::abs(mean), 5 * sigmas[j] / std::sqrt(n)) << "joint " << j + 1;
  }
  EXPECT_EQ(noise.col(2).cwiseAbs().maxCoeff(), 0);
  EXPECT_EQ(log.q, trial.q);  // positions exact

  // Same scene and seed: the same bytes, also from a fresh load and run.
  const std::string csv = ArmSceneTrajectoryCsv(s, trial);
  EXPECT_EQ(ArmSceneTrajectoryCsv(s, trial), csv);
  const ArmScene again = LoadSensorScene(hold, "sensors: {torque_noise: [0.02, 0.5, 0]}\n");
  EXPECT_EQ(ArmSceneTrajectoryCsv(again, RunScene(again)), csv);
  // Another seed: other noise on the same motion.
  ArmScene other = again;
  other.seed = 8;
  EXPECT_NE(ArmSceneTrajectoryCsv(other, trial), csv);
  // Each joint has its own stream: joint 2's noise does not depend on joint 1's.
  const ArmScene quiet_first = LoadSensorScene(hold, "sensors: {torque_noise: [0, 0.5, 0]}\n");
  const ArmLog quiet = SensedArmLog(quiet_first.sensors, trial, quiet_first.seed);
  EXPECT_EQ(quiet.tau.col(0), trial.command.col(0));
  EXPECT_EQ(quiet.tau.col(1), log.tau.col(1));
}

TEST(ArmSceneSensors, LogWithoutVelocitiesReadsBackWithDerivedQd) {
  const ArmScene s = LoadSensorScene(
      kSine, "sensors:\n  encoder_counts_per_rev: 40000\n  torque_noise: 0.02\n  log_velocities: false\n");
  EXPECT_FALSE(s.sensors.log_velocities);
  const TrackingTrial trial = RunScene(s);
  const std::string dir = testing::TempDir("arm_scene_sensors");
  const std::string path = testing::WriteText(dir + "/trajectory.csv", ArmSceneTrajectoryCsv(s, trial));
  EXPECT_EQ(ReadCsvTable(path).header, (std::vector<std::string>{"t", "q1", "q2", "q3", "tau1", "tau2", "tau3",
                                                                  "qref1", "qref2", "qref3"}));
  const ArmLog log = ReadArmLog(path);
  ASSERT_EQ(log.rows(), trial.t.size());
  EXPECT_FALSE(log.qd_logged);
  EXPECT_GT(log.derive_cutoff_hz, 0);
  ASSERT_EQ(log.qd.rows(), log.rows());
  // Away from the ends and the start-up transient, the velocity derived from the whole
  // counts follows the realised one (peak 0.3..0.5 * pi rad/s).
  const int first = std::max(log.edge_samples, 500), last = log.rows() - log.edge_samples;
  for (int j = 0; j < 3; ++j) {
    const double error = (log.qd.middleRows(first, last - first) - trial.qd.middleRows(first, last - first))
                             .col(j).cwiseAbs().maxCoeff();
    EXPECT_LT(error, 0.01) << "joint " << j + 1;  // rad/s
  }
}

TEST(ArmSceneSensors, PrismaticJointsTakeTheirResolutionInMetres) {
  const std::string dir = testing::TempDir("arm_scene_sensors_rp");
  testing::WriteText(dir + "/rp.urdf", R"(<robot name="rp">
  <link name="base"/>
  <joint name="turn" type="revolute">
    <parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="3"/>
  </joint>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="slide" type="prismatic">
    <parent link="l1"/><child link="l2"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" effort="50" velocity="1"/>
  </joint>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
)");
  const std::string head = "name: rp\nrobot: arm\nmodel: rp.urdf\ntask: {type: hold, q: [0, 0.2], duration: 1}\n";
  const ArmScene s = LoadArmSceneFromString(
      head + "sensors: {encoder_counts_per_rev: 4096, encoder_resolution: 1e-5, torque_noise: [0.01, 0.5]}\n", "a.yaml",
      dir);
  ASSERT_EQ(s.sensors.count_step.size(), 2);
  EXPECT_EQ(s.sensors.count_step[0], 2 * kPi / 4096);  // rad
  EXPECT_EQ(s.sensors.count_step[1], 1e-5);             // m
  // Only counts: the prismatic joint stays exact.
  const ArmScene counts_only =
      LoadArmSceneFromString(head + "sensors: {encoder_counts_per_rev: 4096}\n", "a.yaml", dir);
  EXPECT_EQ(counts_only.sensors.count_step[1], 0);

  // A made-up trial: the slide rounded to whole counts of 10 um.
  TrackingTrial trial;
  trial.sample_time = 0.001;
  trial.t = Eigen::VectorXd::LinSpaced(5, 0, 0.004);
  trial.q.resize(5, 2);
  trial.q << 0.1, 0.123456, 0.2, 0.223451, 0.3, 0.000004, 0.4, 0.000006, 0.5, 0.499994;
  trial.qd = trial.command = trial.q_ref = Eigen::MatrixXd::Zero(5, 2);
  const ArmLog log = SensedArmLog(s.sensors, trial, s.seed);
  const Eigen::VectorXd expected = (Eigen::VectorXd(5) << 0.12346, 0.22345, 0, 0.00001, 0.49999).finished();
  EXPECT_LT((log.q.col(1) - expected).cwiseAbs().maxCoeff(), 1e-15);

  // Counts given for the prismatic joint, or a resolution for the revolute one.
  auto error_of = [&](const std::string& sensors) {
    try {
      LoadArmSceneFromString(head + sensors, "a.yaml", dir);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string counts = error_of("sensors:\n  encoder_counts_per_rev: [4096, 100]\n");
  EXPECT_NE(counts.find("a.yaml:6:34: 'encoder_counts_per_rev[1]' in 'sensors': joint 2 ('slide') is prismatic"),
            std::string::npos)
      << counts;
  const std::string resolution = error_of("sensors:\n  encoder_resolution: [1e-6, 1e-6]\n");
  EXPECT_NE(resolution.find("a.yaml:6:24: 'encoder_resolution[0]' in 'sensors': joint 1 ('turn') is revolute"),
            std::string::npos)
      << resolution;
}

TEST(ArmSceneSensors, BadKeysAreReportedWithFileLineAndColumn) {
  const std::string e = ArmSceneErrorOf(SensorScene("{type: writing}",
                                            "sensors:\n"
                                            "  encoder_counts: 40000\n"
                                            "  torque_noise: [0.1, 0.2]\n"
                                            "  encoder_counts_per_rev: 1000.5\n"
                                            "  log_velocities: maybe\n"
                                            "  encoder_resolution: 1e-6\n"));
  EXPECT_NE(e.find("a.yaml:7:3: unknown key 'encoder_counts' in 'sensors' (known: encoder_counts_per_rev, "
                   "encoder_resolution, log_velocities, torque_noise)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("a.yaml:8:17: 'torque_noise' in 'sensors': expected 3 numbers, got 2"), std::string::npos) << e;
  EXPECT_NE(e.find("a.yaml:9:27: 'encoder_counts_per_rev' in 'sensors': expected a whole number of counts, got 1000.5"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("a.yaml:10:19: 'log_velocities' in 'sensors': expected true or false, got 'maybe'"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("a.yaml:11:23: 'encoder_resolution' in 'sensors': 'rrr' has no prismatic joint"), std::string::npos)
      << e;

  const std::string ranges = ArmSceneErrorOf(SensorScene("{type: writing}",
                                                 "sensors:\n"
                                                 "  torque_noise: [0.1, -0.2, 0]\n"
                                                 "  encoder_counts_per_rev: 2e9\n"));
  EXPECT_NE(ranges.find("a.yaml:7:23: 'torque_noise' in 'sensors'[1]: must not be negative, got -0.2"),
            std::string::npos)
      << ranges;
  EXPECT_NE(ranges.find("a.yaml:8:27: 'encoder_counts_per_rev' in 'sensors': must be in [0, 1e+09], got 2e+09"),
            std::string::npos)
      << ranges;

  const std::string shape = ArmSceneErrorOf(SensorScene("{type: writing}", "sensors: {torque_noise: {j1: 0.1}}\n"));
  EXPECT_NE(shape.find("a.yaml:6:25: 'torque_noise' in 'sensors': expected a number or a list of 3 numbers"),
            std::string::npos)
      << shape;
  const std::string scalar = ArmSceneErrorOf(SensorScene("{type: writing}", "sensors: 40000\n"));
  EXPECT_NE(scalar.find("a.yaml:6:10: 'sensors': expected a mapping"), std::string::npos) << scalar;
}

}  // namespace
}  // namespace twinsim
