#include "scene/scene.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

std::string SceneErrorOf(const std::string& yaml) { return testing::SceneError(yaml); }

TEST(Scene, ShippedScenesLoad) {
  for (const char* name : {"drive45", "steps", "figure_eight", "go_to_pose", "random_excitation", "record_plant",
                           "go_to_pose_straight", "go_to_pose_predicted"}) {
    Scene s = LoadScene(SourcePath(std::string("scenes/") + name + ".yaml"));
    EXPECT_EQ(s.name, name);
    EXPECT_FALSE(s.robots.empty());
  }
}

TEST(Scene, TimingDefaultsToAtLeast300HzPhysics) {
  Scene s = LoadSceneFromString(
      "name: t\nframe_rate: 60\nduration: 1\nrobots:\n  - model: ../models/omni4.yaml\n    commands: {type: random}\n",
      "s.yaml", SourcePath("scenes"));
  EXPECT_EQ(s.timing().physics_substeps, 5);  // grSim: 5 steps per 60 fps frame
  EXPECT_EQ(s.num_frames(), 61);
}

TEST(Scene, UnknownKeyWrongTypeMissingFieldAndBadModel) {
  const std::string e = SceneErrorOf(
      "name: t\n"
      "duration: long\n"
      "robots:\n"
      "  - model: ../models/nope.yaml\n"
      "    commands: {type: test_drive, sped: 2}\n"
      "  - model: ../models/omni4.yaml\n");
  EXPECT_NE(e.find("s.yaml:2:11: 'duration': expected a number, got 'long'"), std::string::npos) << e;
  EXPECT_NE(e.find("nope.yaml: cannot open file"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:5:34: unknown key 'sped' in 'robots[0].commands'"), std::string::npos) << e;
  EXPECT_NE(e.find("missing required key 'commands' in 'robots[1]'"), std::string::npos) << e;
}

TEST(Scene, RobotsAreBlueWithIdsInOrderUnlessTheySay) {
  const std::string robot = "    model: ../models/omni4.yaml\n    commands: {type: random}\n";
  Scene s = LoadSceneFromString("name: t\nduration: 1\nrobots:\n  - name: a\n    id: 0\n" + robot +
                                    "  - name: b\n" + robot + "  - name: c\n    team: yellow\n" + robot +
                                    "  - name: d\n    team: yellow\n    id: 0\n" + robot,
                                "s.yaml", SourcePath("scenes"));
  ASSERT_EQ(s.robots.size(), 4u);
  EXPECT_EQ(s.robots[0].team + std::to_string(s.robots[0].id), "blue0");
  EXPECT_EQ(s.robots[1].team + std::to_string(s.robots[1].id), "blue1");
  EXPECT_EQ(s.robots[2].team + std::to_string(s.robots[2].id), "yellow1");  // 0 is d's
  EXPECT_EQ(s.robots[3].team + std::to_string(s.robots[3].id), "yellow0");
}

TEST(Scene, TeamsAndIdsAreChecked) {
  const std::string robot = "    model: ../models/omni4.yaml\n    commands: {type: random}\n";
  const std::string e = SceneErrorOf("name: t\nduration: 1\nrobots:\n  - name: a\n    id: 2\n" + robot +
                                "  - name: b\n    id: 2\n" + robot + "  - name: c\n    team: red\n" + robot +
                                "  - name: d\n    id: 16\n" + robot);
  EXPECT_NE(e.find("s.yaml:9:9: robots[1]: blue robot id 2 is taken by robot 'a'"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown value 'red' (known: blue, yellow)"), std::string::npos) << e;
  EXPECT_NE(e.find("must be in [0, 15], got 16"), std::string::npos) << e;
}

TEST(Scene, ARobotMayStartOffTheFieldAndPresentIsChecked) {
  const std::string robot = "    model: ../models/omni4.yaml\n    commands: {type: random}\n";
  Scene s = LoadSceneFromString("name: t\nduration: 1\nrobots:\n  - name: a\n" + robot +
                                    "  - name: b\n    present: false\n" + robot,
                                "s.yaml", SourcePath("scenes"));
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_TRUE(s.robots[0].present);  // the default
  EXPECT_FALSE(s.robots[1].present);
  const std::string e = SceneErrorOf("name: t\nduration: 1\nrobots:\n  - name: a\n    present: maybe\n" + robot);
  EXPECT_NE(e.find("s.yaml:5:14: 'present' in 'robots[0]': expected true or false, got 'maybe'"), std::string::npos) << e;
}

TEST(Scene, UnknownCommandTypeListsKnownOnes) {
  const std::string e = SceneErrorOf("name: t\nduration: 1\nrobots:\n  - model: ../models/omni4.yaml\n    commands: {type: dance}\n");
  EXPECT_NE(e.find("unknown value 'dance' (known: sequence, test_drive, figure_eight, random, go_to_pose, log)"),
            std::string::npos)
      << e;
}

TEST(Scene, SegmentNeedsExactlyOneOfCommandOrRamp) {
  const std::string e = SceneErrorOf(
      "name: t\nduration: 1\nrobots:\n  - model: ../models/omni4.yaml\n    commands:\n      type: sequence\n"
      "      segments:\n        - {duration: 1}\n");
  EXPECT_NE(e.find("give exactly one of 'command' (hold) or 'ramp_to' (ramp)"), std::string::npos) << e;
}

}  // namespace
}  // namespace twinsim
