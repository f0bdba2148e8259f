#include "tuning/tuned_pid_yaml.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "robots/omni/omni_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(TunedPidYaml, ExtendsTheModelFileWithTheLearnedControllers) {
  const std::string dir = testing::TempDir("tuned_pid_yaml");
  const std::string scene_path =
      testing::WriteText(dir + "/run.yaml", "name: run\nduration: 3.2\nrobots:\n  - name: a\n    model: " +
                                                testing::SourcePath("models/omni4.yaml") +
                                                "\n    commands: {type: test_drive, drive_time: 1.5}\n");
  const TestRunEvaluator evaluator(LoadScene(scene_path), "analytic", {});
  PidTuningResult r;
  r.best_parameters = Eigen::VectorXd::LinSpaced(kPidParameters, 1, 18) / 7.0;
  r.iterations.resize(4);
  r.search.best_iteration = 2;
  r.test_runs = 84;
  r.best_score.quality = 0.5;
  r.best_score.distance = 1.25;
  r.best_score.avg_speed = 1.0 / 3;
  r.best_score.end_deviation_pct = 2;
  const std::string text = FormatTunedPidYaml(evaluator, r, dir + "/out");
  // The model file, relative to the folder pid.yaml goes into.
  const std::string extends = std::filesystem::absolute(testing::SourcePath("models/omni4.yaml"))
                                  .lexically_relative(std::filesystem::absolute(dir + "/out"))
                                  .string();
  EXPECT_EQ(text,
            "# PID parameters learned by `twinsim tune-pid " + scene_path +
                "` on analytic\n"
                "# (policy gradient, seed 000 section 3.4): iteration 2 of 4, 84 test runs.\n"
                "# Its test run: quality 0.5, distance 1.25 m, average speed 0.3333333333 m/s, end deviation 2 %.\n"
                "extends: " + extends + "\n"
                "name: omni4_tuned\n"
                "controller:\n"
                "  forward: {kp: 0.1428571429, ki: 0.2857142857, kd: 0.4285714286, integral_limit: 0.5714285714, "
                "output_limit: 0.7142857143, slew_rate: 0.8571428571}\n"
                "  sideways: {kp: 1, ki: 1.142857143, kd: 1.285714286, integral_limit: 1.428571429, "
                "output_limit: 1.571428571, slew_rate: 1.714285714}\n"
                "  rotation: {kp: 1.857142857, ki: 2, kd: 2.142857143, integral_limit: 2.285714286, "
                "output_limit: 2.428571429, slew_rate: 2.571428571}\n")
      << text;
  // It loads as a model: the original with the learned controller.
  std::filesystem::create_directories(dir + "/out");
  testing::WriteText(dir + "/out/pid.yaml", text);
  const OmniModel tuned = LoadOmniModel(dir + "/out/pid.yaml");
  EXPECT_EQ(tuned.name, "omni4_tuned");
  EXPECT_NEAR(tuned.controller.rotation.slew_rate, 18.0 / 7, 1e-9);
  EXPECT_EQ(tuned.total_mass, LoadOmniModel(testing::SourcePath("models/omni4.yaml")).total_mass);
}

}  // namespace
}  // namespace twinsim
