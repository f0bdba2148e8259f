#include "backends/omni_backend_factory.h"
#include "sim/omni_simulation.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "scene/command_source.h"
#include "scene/scene.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(Simulation, DivergenceIsAnErrorThatSaysWhereAndWhen) {
  // A controller far too stiff for its 300 Hz loop, with motors that never saturate:
  // the velocity loop is unstable and the robot runs away within a few frames.
  OmniModel m = testing::Omni4();
  m.controller.forward.kp = 1e6;
  m.controller.forward.output_limit = 1e12;
  m.motor_stall_torque = 1e9;
  m.motor_no_load_speed = 1e12;
  CommandSpec spec;
  spec.type = "sequence";
  spec.segments = {{1.0, Twist2{1.0, 0, 0}, false}};
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"wild", m, Pose2{}, MakeCommandSource(spec, 1, 0, 1, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {m}, FieldModel{}, FrameTiming{}), 1);
  try {
    sim.Run(60);
    FAIL() << "expected the simulation to diverge";
  } catch (const CheckFailed& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("simulation diverged at t = "), std::string::npos) << msg;
    EXPECT_NE(msg.find("robot 'wild' on backend analytic"), std::string::npos) << msg;
    // The last good state is the frame before, finite and at a plausible speed.
    const std::size_t at = msg.find("last good state at t = ");
    ASSERT_NE(at, std::string::npos) << msg;
    EXPECT_NE(msg.find(" vx = ", at), std::string::npos) << msg;
    EXPECT_EQ(msg.find("nan", at), std::string::npos) << msg;
    EXPECT_EQ(msg.find("inf", at), std::string::npos) << msg;
  }
}

TEST(Simulation, UncompiledBackendSaysHowToRebuild) {
  const std::vector<std::string> built = AvailableOmniBackends();
  for (const auto& [name, flag] : {std::pair{"ode", "TWINSIM_WITH_ODE"}, std::pair{"bullet", "TWINSIM_WITH_BULLET"}}) {
    if (std::find(built.begin(), built.end(), name) != built.end()) continue;
    try {
      MakeOmniBackend(name, {testing::Omni4()}, FieldModel{}, FrameTiming{});
      FAIL() << name << " should not be available";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("-D") + flag + "=ON"), std::string::npos) << e.what();
    }
  }
}

TEST(Simulation, LostFramesAreLeftOutAtTheModelsRate) {
  OmniModel m = testing::Omni4();
  m.vision_drop_probability = 0.3;
  CommandSpec spec;
  spec.type = "random";
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", m, Pose2{}, MakeCommandSource(spec, 2, 0, 5, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {m}, FieldModel{}, FrameTiming{}), 2);
  SimulationResult r = sim.Run(151);
  int lost = 0;
  for (const auto& f : r.frames[0]) lost += !f.observed;
  // 30 % of 151 frames: 45 expected, binomial sd 5.6.
  EXPECT_GT(lost, 25);
  EXPECT_LT(lost, 65);
}

// The ball's camera (a scene's ball.vision): the noise has the asked spread around the
// truth captured vision_frames earlier, a lost frame delivers no ball, and the robots'
// own noise is untouched by it.
TEST(Simulation, TheBallsCameraNoiseAndLostFramesComeFromTheirOwnStream) {
  auto run = [](const BallVision& vision) {
    const std::string model = testing::SourcePath("models/omni4.yaml");
    Scene scene = LoadSceneFromString("name: b\nbackend: analytic\nframe_rate: 60\nduration: 20\nseed: 3\nrobots:\n"
                                      "  - {name: r, model: " + model + ", commands: {type: random, max_speed: 1, leash: 0.5}}\n"
                                      "ball: {start: {x: 1, y: 0.5, vx: -0.5, vy: 1.0}}\n",
                                      "b.yaml", ".");
    scene.ball->vision = vision;
    return MakeSimulation(scene, "analytic").Run(scene.num_frames());
  };
  BallVision noisy;
  noisy.noise_xy = 0.002;
  noisy.noise_z = 0.001;
  noisy.drop_probability = 0.2;
  const SimulationResult exact = run(BallVision{}), seen = run(noisy);
  const int delay = testing::Omni4().vision_delay_frames;
  int lost = 0, n = 0;
  double sxx = 0, szz = 0;
  for (std::size_t k = static_cast<std::size_t>(delay); k < seen.ball.size(); ++k) {
    EXPECT_TRUE(exact.ball[k].observed);
    EXPECT_EQ(exact.ball[k].seen, exact.ball[k - static_cast<std::size_t>(delay)].truth.position);
    if (!seen.ball[k].observed) {
      ++lost;
      continue;
    }
    const Eigen::Vector3d e = seen.ball[k].seen - seen.ball[k - static_cast<std::size_t>(delay)].truth.position;
    sxx += e.x() * e.x() + e.y() * e.y();
    szz += e.z() * e.z();
    ++n;
  }
  // 1198 frames: 20 % lost is 240 expected, binomial sd 14; the spreads from ~960 draws
  // (x and y: ~1900) within 10 %.
  EXPECT_NEAR(lost, 240, 60);
  EXPECT_NEAR(std::sqrt(sxx / (2 * n)), 0.002, 0.0002);
  EXPECT_NEAR(std::sqrt(szz / n), 0.001, 0.0001);
  // The robot's observations and the ball's true path are those of the exact camera.
  for (std::size_t k = 0; k < seen.frames[0].size(); ++k) {
    EXPECT_EQ(seen.frames[0][k].seen.x, exact.frames[0][k].seen.x) << k;
    EXPECT_EQ(seen.ball[k].truth.position, exact.ball[k].truth.position) << k;
  }
}

}  // namespace
}  // namespace twinsim
