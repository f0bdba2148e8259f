#include "backends/omni_backend_factory.h"
#include "sim/omni_simulation.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "scene/command_source.h"
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

}  // namespace
}  // namespace twinsim
