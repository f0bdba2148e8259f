// The plots of a scene's `plots:` list: which files, which paths and series, which titles.
#include "scene/scene_plots.h"

#include <gtest/gtest.h>

#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

// Two robots standing still for three frames; the second robot's middle frame is lost.
SimulationResult StandingResult() {
  SimulationResult result;
  result.robot_names = {"a", "b"};
  for (int r = 0; r < 2; ++r) {
    std::vector<FrameRecord> frames(3);
    for (int k = 0; k < 3; ++k) {
      frames[static_cast<std::size_t>(k)].t = k / 30.0;
      frames[static_cast<std::size_t>(k)].truth = Pose2{r * 1.0, 0, 0};
      frames[static_cast<std::size_t>(k)].seen = Pose2{r * 1.0, 0.01, 0};
      frames[static_cast<std::size_t>(k)].observed = !(r == 1 && k == 1);
    }
    result.frames.push_back(frames);
  }
  return result;
}

TEST(ScenePlots, OmniPathsPerRobotAndSourceInTheListsOrder) {
  const Scene scene = LoadSceneFromString(
      "name: two\nduration: 0.1\nrobots:\n"
      "  - {name: a, model: ../models/omni4.yaml, commands: {type: random}}\n"
      "  - {name: b, model: ../models/omni4.yaml, start: {x: 1}, commands: {type: random}}\n"
      "plots:\n"
      "  - {type: path, file: truth.png}\n"
      "  - {type: path, file: both.png, source: both, region: field, title: '{scene} on {backend}'}\n",
      "s.yaml", SourcePath("scenes"));
  const std::vector<ScenePlot> plots = ScenePlots(scene, StandingResult(), "ode");
  ASSERT_EQ(plots.size(), 2u);
  EXPECT_EQ(plots[0].file, "truth.png");
  const PathPlot& truth = std::get<PathPlot>(plots[0].plot);
  ASSERT_EQ(truth.paths.size(), 2u);  // several robots: the truth by default
  EXPECT_EQ(truth.paths[1].name, "b");
  const PathPlot& both = std::get<PathPlot>(plots[1].plot);
  EXPECT_EQ(both.title, "two on ode");
  ASSERT_EQ(both.paths.size(), 4u);
  EXPECT_EQ(both.paths[0].name, "a truth");
  const int late = scene.robots[1].model.vision_delay_frames;
  EXPECT_EQ(both.paths[3].name, "b seen by the observer (" + std::to_string(late) + " frames late)");
  // Only the frames that arrived, numbered by the frame they were captured in.
  EXPECT_EQ(both.paths[3].frames, (std::vector<int>{0 - late, 2 - late}));
  ASSERT_TRUE(both.region.has_value());
  EXPECT_NEAR(both.region->x_max, scene.field.length / 2 + 0.15, 1e-12);
}

TEST(ScenePlots, ArmJointTorquesGiveOnePlotPerJoint) {
  const ArmScene scene = LoadArmSceneFromString(
      "name: hold\nrobot: arm\nmodel: ../models/rrr.yaml\n"
      "task: {type: hold, q: [0, 0.8, -1.5], duration: 0.05}\n"
      "plots:\n"
      "  - {type: tool_path, file: path.png, width: 800, height: 600}\n"
      "  - {type: joint_torques, file: torque.png}\n"
      "  - {type: tracking_error, file: error.png, title: 'error of {scene}'}\n",
      "a.yaml", SourcePath("scenes"));
  const TrackingTrial trial = RunTrackingTrial(scene.plant, scene.hat, ArmSceneReference(scene), scene.tracking);
  const std::vector<ScenePlot> plots = ArmScenePlots(scene, trial, "analytic");
  ASSERT_EQ(plots.size(), 5u);
  EXPECT_EQ(plots[0].file, "path.png");
  EXPECT_EQ(std::get<PathPlot>(plots[0].plot).width, 800);
  EXPECT_EQ(std::get<PathPlot>(plots[0].plot).title, "hold (analytic): tool point path");
  EXPECT_EQ(plots[1].file, "torque_joint1.png");
  EXPECT_EQ(plots[3].file, "torque_joint3.png");
  EXPECT_EQ(std::get<SeriesPlot>(plots[3].plot).title, "hold (analytic): joint 3 torque");
  EXPECT_EQ(plots[4].file, "error.png");
  EXPECT_EQ(std::get<SeriesPlot>(plots[4].plot).title, "error of hold");
}

}  // namespace
}  // namespace twinsim
