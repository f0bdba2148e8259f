#include "tuning/pid_tuning.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "test_util.h"
#include "tuning/pid_baselines.h"

namespace twinsim {
namespace {

using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;
using testing::WriteText;

// A test run's frames, drawn by hand: at rest, along 45 degrees to the heading
// (theta_0 = 30 deg), a sideways offset of 5 cm at the end, a 0.1 rad wobble, seen
// without delay at 10 Hz.
std::vector<FrameRecord> HandDrawnRun(TestDrive* drive) {
  drive->start = 0.5;
  drive->drive_time = 1.0;
  drive->direction = kPi / 4;
  drive->frame_rate = 10;
  drive->command_delay_frames = 1;
  drive->vision_delay_frames = 0;
  const double a = kPi / 6 + kPi / 4;
  const Eigen::Vector2d u(std::cos(a), std::sin(a)), n(-std::sin(a), std::cos(a));
  std::vector<FrameRecord> frames;
  for (int k = 0; k <= 30; ++k) {
    const double t = k / 10.0;
    // along: 0 until 0.5 s, 1 m/s until the stop acts at 1.6 s (1.1 m), then 0.3 m more.
    const double along = t < 0.5 ? 0 : t < 1.6 ? t - 0.5 : std::min(1.4, 1.1 + (t - 1.6));
    const double side = along / 1.4 * 0.05;
    const Eigen::Vector2d p = Eigen::Vector2d(1, 2) + along * u + side * n;
    FrameRecord f;
    f.t = t;
    f.observed = k != 7;  // one lost frame
    f.seen = Pose2{p.x(), p.y(), kPi / 6 + (k == 12 ? 0.1 : 0.0)};
    frames.push_back(f);
  }
  return frames;
}

TEST(PidTuning, ScoresAHandDrawnTestRun) {
  TestDrive drive;
  const std::vector<FrameRecord> frames = HandDrawnRun(&drive);
  QualityWeights w;
  w.distance = 1, w.deviation = 2, w.rotation = 0.5, w.stop_distance = 1;
  const TestRunScore s = ScoreTestRun(frames, drive, w);
  EXPECT_NEAR(s.distance, 1.1, 1e-9);  // at t = 1.6 s, when the stop acts
  EXPECT_NEAR(s.stop_distance, std::hypot(0.3, 0.05 * 0.3 / 1.4), 1e-9);
  EXPECT_NEAR(s.deviation, 0.05, 1e-9);
  EXPECT_NEAR(s.rotation, 0.1, 1e-12);
  EXPECT_NEAR(s.avg_speed, 1.1, 1e-9);
  EXPECT_NEAR(s.end_deviation_pct, 0.05 / 1.4 * 100, 1e-9);
  EXPECT_NEAR(s.quality, 1.1 - 2 * 0.05 - 0.5 * 0.1 - s.stop_distance, 1e-12);
}

TEST(PidTuning, ARunWithNoFrameSeenIsBadInput) {
  // A scene whose camera drops every frame: the user's scene, not our bug (exit 2).
  TestDrive drive;
  std::vector<FrameRecord> frames = HandDrawnRun(&drive);
  for (FrameRecord& f : frames) f.observed = false;
  try {
    ScoreTestRun(frames, drive, QualityWeights{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "test run: no frame was observed");
  }
}

TEST(PidTuning, ParameterVectorRoundTrip) {
  const OmniControllerModel c;
  const Eigen::VectorXd p = PidParameters(c);
  ASSERT_EQ(p.size(), 18);
  EXPECT_EQ(p[0], c.forward.kp);
  EXPECT_EQ(p[17], c.rotation.slew_rate);
  EXPECT_EQ(PidParameters(WithPidParameters(OmniControllerModel{}, 2 * p)), 2 * p);
  EXPECT_EQ(PidParameterNames()[10], "sideways.output_limit");
}

Scene ZerosScene() { return LoadScene(SourcePath("scenes/tune_pid_zeros.yaml")); }

// Seed 000, section 3.4: from all zeros the robot does not move; within 10 iterations
// of 20 test runs it drives at least 1 m/s on average and ends within 10 % of its line.
TEST(PidTuning, LearnsToDriveFromZeros) {
  const Scene scene = ZerosScene();
  const PidTuningOptions o = ReadPidTuningOptions(scene);
  ASSERT_EQ(o.start, "zeros");
  ASSERT_EQ(o.iterations, 10);
  const TestRunEvaluator evaluator(scene, "ode", o.weights);
  const PidTuningResult r = TunePid(evaluator, o);
  EXPECT_LT(std::abs(r.iterations.front().score.distance), 0.01);  // does not move at first
  EXPECT_GE(r.best_score.avg_speed, 1.0);
  EXPECT_LE(r.best_score.end_deviation_pct, 10.0);
  EXPECT_EQ(r.test_runs, 10 * 21);
}

// Learning from the hand-tuned set (all three controllers) improves on it.
TEST(PidTuning, ImprovesOnTheHandTunedSet) {
  Scene scene = ZerosScene();
  PidTuningOptions o = ReadPidTuningOptions(scene);
  o.start = "model";
  const TestRunEvaluator evaluator(scene, "ode", o.weights);
  const PidTuningResult r = TunePid(evaluator, o);
  EXPECT_GT(r.best_score.quality, r.iterations.front().score.quality + 0.05);
  EXPECT_GT(r.search.best_iteration, 0);
}

// Relearning after a mechanical change: 1.5 kg more costs the hand-tuned set quality;
// relearning wins it back (to at least what the light robot had).
TEST(PidTuning, RelearnsAfterTheRobotGetsHeavier) {
  const Scene light = ZerosScene();
  const Scene heavy = LoadScene(SourcePath("scenes/tune_pid_relearn_heavy.yaml"));
  const PidTuningOptions o = ReadPidTuningOptions(heavy);
  ASSERT_EQ(o.start, "model");
  const TestRunEvaluator on_light(light, "ode", o.weights), on_heavy(heavy, "ode", o.weights);
  const Eigen::VectorXd hand = PidParameters(OmniControllerModel{});
  const double before = on_light.Evaluate(hand).quality, after_change = on_heavy.Evaluate(hand).quality;
  EXPECT_LT(after_change, before - 0.05);
  const PidTuningResult r = TunePid(on_heavy, o);
  EXPECT_GE(r.best_score.quality, before);
}

// The same seed gives the same learning with one or two worker threads.
TEST(PidTuning, DeterministicWhateverTheThreadCount) {
  const Scene scene = ZerosScene();
  PidTuningOptions o = ReadPidTuningOptions(scene);
  o.iterations = 3;
  const TestRunEvaluator evaluator(scene, "ode", o.weights);
  o.threads = 1;
  const PidTuningResult one = TunePid(evaluator, o);
  o.threads = 2;
  const PidTuningResult two = TunePid(evaluator, o);
  ASSERT_EQ(one.iterations.size(), two.iterations.size());
  for (std::size_t i = 0; i < one.iterations.size(); ++i) {
    EXPECT_EQ(one.iterations[i].parameters, two.iterations[i].parameters);
    for (std::size_t k = 0; k < one.iterations[i].tested.size(); ++k)
      EXPECT_EQ(one.iterations[i].tested[k].quality, two.iterations[i].tested[k].quality);
  }
}

// Ziegler-Nichols' experiment on the analytic model: P-only control oscillates for good
// at the ultimate gain and above it, and settles below it.
TEST(PidBaselines, UltimateGainSeparatesDecayFromSustainedOscillation) {
  const Scene scene = ZerosScene();
  const TestRunEvaluator evaluator(scene, "analytic", QualityWeights{});
  const Eigen::VectorXd hand = PidParameters(OmniControllerModel{});
  const UltimateGain u = FindUltimateGain(evaluator, hand, 0, 30);
  ASSERT_GT(u.ku, 0);
  // The loop runs at 300 Hz with a one-tick measurement lag: the oscillation at the
  // ultimate gain has a period of a few ticks.
  EXPECT_GT(u.tu, 2.0 / 300);
  EXPECT_LT(u.tu, 20.0 / 300);
  EXPECT_LE(u.experiments, 30);
  const UltimateGain again = FindUltimateGain(evaluator, hand, 0, 30);
  EXPECT_EQ(again.ku, u.ku);
}

TEST(PidTuning, RejectsScenesThatAreNotTestRuns) {
  const std::string dir = TempDir("pid_tuning_bad");
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string two = WriteText(dir + "/two.yaml", "name: two\nduration: 3\nrobots:\n"
                                    "  - {name: a, model: " + model + ", commands: {type: test_drive}}\n"
                                    "  - {name: b, model: " + model + ", start: {x: 1}, commands: {type: test_drive}}\n");
  EXPECT_THROW(TestRunEvaluator(LoadScene(two), "ode", {}), InputError);
  const std::string figure = WriteText(dir + "/figure.yaml", "name: f\nduration: 3\nrobots:\n"
                                       "  - {name: a, model: " + model + ", commands: {type: figure_eight}}\n");
  try {
    TestRunEvaluator(LoadScene(figure), "ode", {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("test_drive"), std::string::npos) << e.what();
  }
  const std::string short_run = WriteText(dir + "/short.yaml", "name: s\nduration: 2\nrobots:\n"
                                          "  - {name: a, model: " + model + ", commands: {type: test_drive}}\n");
  EXPECT_THROW(TestRunEvaluator(LoadScene(short_run), "ode", {}), InputError);
}

TEST(PidTuning, BadTunePidBlockIsExitCode2WithFileAndLine) {
  const std::string dir = TempDir("pid_tuning_block");
  std::string text = testing::ReadText(SourcePath("scenes/tune_pid_zeros.yaml"));
  text = text.substr(0, text.find("tune_pid:"));
  const std::string model = SourcePath("models/omni4.yaml");
  text.replace(text.find("../models/omni4.yaml"), 20, model);
  const std::string path = WriteText(dir + "/scene.yaml", text + "tune_pid:\n  start: zeros\n  learn: [forward, yaw]\n  etta: 0.1\n");
  const testing::CommandResult r = RunTwinsim("tune-pid " + path + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("scene.yaml:22:20: tune_pid.learn"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown controller 'yaw'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown key 'etta'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/learning.csv"));
}

TEST(PidTuning, CommandWritesTheContractFiles) {
  const std::string dir = TempDir("pid_tuning_cli");
  const testing::CommandResult r =
      RunTwinsim("tune-pid " + SourcePath("scenes/tune_pid_zeros.yaml") + " --out " + dir + " --iterations 3 -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = testing::ReadText(dir + "/learning.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "iteration,quality,distance,deviation,rotation,stop_distance,avg_speed,end_deviation_pct");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);
  // pid.yaml is a model file: the robot with the learned controller.
  const OmniModel tuned = LoadOmniModel(dir + "/pid.yaml");
  const OmniModel base = LoadOmniModel(SourcePath("models/omni4.yaml"));
  EXPECT_EQ(tuned.total_mass, base.total_mass);
  EXPECT_EQ(tuned.name, "omni4_tuned");
  // ... the best current set of learning.csv, as parameters.csv lists it.
  auto rows = [](const std::string& text) {
    std::vector<std::vector<double>> out;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::vector<double> row;
      std::istringstream fields(line);
      for (std::string f; std::getline(fields, f, ',');) row.push_back(std::stod(f));
      out.push_back(row);
    }
    return out;
  };
  const auto learning = rows(csv), params = rows(testing::ReadText(dir + "/parameters.csv"));
  std::size_t best = 0;
  for (std::size_t i = 0; i < learning.size(); ++i)
    if (learning[i][1] > learning[best][1]) best = i;
  const Eigen::VectorXd p = PidParameters(tuned.controller);
  for (int k = 0; k < 18; ++k) EXPECT_NEAR(p[k], params[best][k + 1], 1e-8 * (1 + std::abs(p[k]))) << k;
}

}  // namespace
}  // namespace twinsim
