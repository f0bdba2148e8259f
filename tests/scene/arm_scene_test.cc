// Arm scenes: the shipped ones load, references of each task type, and bad input.
#include "scene/arm_scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

std::string ErrorOf(const std::string& yaml) {
  try {
    LoadArmSceneFromString(yaml, "a.yaml", SourcePath("scenes"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ArmScene, ShippedScenesLoadAndAreArmScenes) {
  const ArmScene bare = LoadArmScene(SourcePath("scenes/rrr_writing.yaml"));
  EXPECT_EQ(SceneRobotKind(SourcePath("scenes/rrr_writing.yaml")), "arm");
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
  EXPECT_EQ(SceneRobotKind(SourcePath("scenes/drive45.yaml")), "omni");
}

TEST(ArmScene, TaskReferencesInClosedForm) {
  const std::string head = "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n";
  // A sinusoid: exact derivatives.
  ArmScene s = LoadArmSceneFromString(
      head + "task: {type: sinusoid, q: [0, 0.8, -1.5], amplitude: [0.2, 0.1, 0], frequency: 2, duration: 0.5}\n",
      "a.yaml", SourcePath("scenes"));
  ArmReference ref = ArmSceneReference(s);
  ASSERT_EQ(ref.t.size(), 501);
  const double w = 4 * M_PI, t = ref.t[123];
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
  const std::string e = ErrorOf(
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

  const std::string sizes = ErrorOf(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n"
      "task: {type: hold, q: [0, 0.8], duration: 1}\n");
  EXPECT_NE(sizes.find("a.yaml:4:"), std::string::npos) << sizes;
  EXPECT_NE(sizes.find("'q'"), std::string::npos) << sizes;

  const std::string limits = ErrorOf(
      "name: a\nrobot: arm\nmodel: ../models/rrr.yaml\n"
      "task: {type: hold, q: [0, 0.8, 9], duration: 1}\n");
  EXPECT_NE(limits.find("joint 3 ('elbow') at 9"), std::string::npos) << limits;

  const std::string missing = ErrorOf("name: a\nrobot: arm\n");
  EXPECT_NE(missing.find("missing required key 'model'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing required key 'task'"), std::string::npos) << missing;

  const std::string hat = ErrorOf(
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

}  // namespace
}  // namespace twinsim
