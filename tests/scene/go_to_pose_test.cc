// Predicting away the delay (seed 000, section 4.1): go-to-pose at 2 m/s on four-frame-
// old observations overshoots; acting on a learned 4-frame prediction does not.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "backends/omni_backend_factory.h"
#include "learning/omni_predictor.h"
#include "robots/omni/omni_effects.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

struct Approach {
  double overshoot = 0;  // m past the target along the approach
  double settled = 0;    // s, from the start until within 2 cm for good
};

// Drives `model` (the robot) to a target 3 m away; a residual predictor carries its
// Newtonian model `nominal` along the observations.
Approach DriveToTarget(const OmniModel& model, std::shared_ptr<const OmniPredictor> predictor,
                       const OmniModel* nominal = nullptr) {
  CommandSpec spec;
  spec.type = "go_to_pose";
  spec.max_speed = 2.0;
  spec.max_accel = 1.8;
  spec.gain = 2.5;
  spec.targets = {Pose2{1.5, 0, 0}};
  spec.predictor = std::move(predictor);
  if (nominal) spec.predictor_model = std::make_shared<const OmniModel>(*nominal);
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{-1.5, 0, 0}, MakeCommandSource(spec, 1, 0, 5, Pose2{-1.5, 0, 0})});
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {model}, FieldModel{}, FrameTiming{}), 4);
  Approach a;
  const SimulationResult result = sim.Run(151);
  for (const FrameRecord& f : result.frames[0]) {
    a.overshoot = std::max(a.overshoot, f.truth.x - 1.5);
    if (std::hypot(f.truth.x - 1.5, f.truth.y) > 0.02) a.settled = f.t;
  }
  return a;
}

TEST(GoToPose, PredictingAwayTheDelayRemovesTheOvershoot) {
  const OmniModel model = testing::Omni4();
  // A 4-frame predictor learned from five minutes of random driving of the same robot.
  const OmniLog drive = testing::RecordLog(model, testing::RandomDrive(2.0, 2.0, 2.0), 300, 7, "analytic", "drive.csv");
  OmniTrainOptions options;
  options.horizon = 4;
  auto predictor = std::make_shared<OmniPredictor>(
      TrainOmniPredictor(model, {drive}, options));

  const Approach plain = DriveToTarget(model, nullptr);
  const Approach predicted = DriveToTarget(model, predictor);
  EXPECT_GT(plain.overshoot, 0.1) << "the delay alone should make it overshoot";
  EXPECT_LT(predicted.overshoot, 0.3 * plain.overshoot)
      << "overshoot " << predicted.overshoot << " m with prediction, " << plain.overshoot << " m without";
  EXPECT_LT(predicted.settled, plain.settled - 0.3)
      << "settled at " << predicted.settled << " s with prediction, " << plain.settled << " s without";
}

// The same with a residual 4-frame predictor on a robot whose motors lag and wheels slip
// (which its Newtonian model does not know): the behaviour carries the Newtonian model
// along its observations and acts on the corrected prediction.
TEST(GoToPose, AResidualPredictorPredictsTheDelayAwayOnARobotWithEffects) {
  const OmniModel nominal = testing::Omni4();
  OmniModel plant = nominal;
  SetOmniEffect("motor_lag", {{"time_constant", 0.08}}, &plant.effects);
  // Grip for the 1.8 m/s^2 of braking the behaviour plans, not for the controller's
  // hardest accelerations.
  SetOmniEffect("traction_limit", {{"a_max", 2.5}}, &plant.effects);
  const OmniLog drive = testing::RecordLog(plant, testing::RandomDrive(2.0, 2.0, 2.0), 300, 7, "analytic", "drive.csv");
  OmniTrainOptions options;
  options.horizon = 4;
  options.residual = true;
  auto predictor = std::make_shared<OmniPredictor>(TrainOmniPredictor(nominal, {drive}, options));
  ASSERT_TRUE(predictor->residual());

  const Approach plain = DriveToTarget(plant, nullptr);
  const Approach predicted = DriveToTarget(plant, predictor, &nominal);
  options.residual = false;
  const Approach seed = DriveToTarget(plant, std::make_shared<OmniPredictor>(TrainOmniPredictor(nominal, {drive}, options)));
  const std::string numbers = "overshoot " + std::to_string(plain.overshoot) + " / " +
                              std::to_string(predicted.overshoot) + " / " + std::to_string(seed.overshoot) +
                              " m, settled " + std::to_string(plain.settled) + " / " + std::to_string(predicted.settled) +
                              " / " + std::to_string(seed.settled) + " s (none / residual / seed's predictor)";
  // The motors' lag still lets it overshoot some (measured: 0.37 -> 0.11 m, as the seed's
  // predictor): what prediction can remove is the delay's share.
  EXPECT_GT(plain.overshoot, 0.1) << numbers;
  EXPECT_LT(predicted.overshoot, 0.4 * plain.overshoot) << numbers;
  EXPECT_LT(predicted.overshoot, seed.overshoot + 0.02) << numbers;
  EXPECT_LT(predicted.settled, plain.settled - 0.5) << numbers;
}

}  // namespace
}  // namespace twinsim
