// Driving noise drawn by the simulation loop (issue 42): with driving_noise.simulated the
// body slips by a first-order Gauss-Markov velocity per robot axis that the wheels and
// the controller never see, on every backend, from a random stream of its own.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "robots/omni/omni_model_yaml_writer.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

OmniModel Slipping(double correlation_time) {
  OmniModel m = testing::Omni4();
  m.driving_noise.simulated = true;
  m.driving_noise.sd = {0.08, 0.05, 0.4};
  m.driving_noise.correlation_time = correlation_time;
  return m;
}

SimulationResult StandStill(const std::string& backend, const OmniModel& model, double seconds, std::uint64_t seed) {
  FrameTiming timing;
  timing.frame_rate = 30;
  timing.physics_substeps = DefaultPhysicsSubsteps(30);
  CommandSpec still;
  still.type = "sequence";
  still.segments = {{seconds, Twist2{}, false}};
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{0, 0, 0}, MakeCommandSource(still, seed, 0, seconds, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend(backend, {model}, FieldModel{}, timing), seed);
  return sim.Run(static_cast<int>(std::lround(seconds * 30)) + 1);
}

// The body's velocity between true poses, in the robot frame (forward, sideways, turn).
std::vector<std::array<double, 3>> BodyVelocities(const SimulationResult& r) {
  std::vector<std::array<double, 3>> v;
  const std::vector<FrameRecord>& f = r.frames[0];
  for (std::size_t k = 0; k + 1 < f.size(); ++k) {
    const double dt = f[k + 1].t - f[k].t;
    const double dx = f[k + 1].truth.x - f[k].truth.x, dy = f[k + 1].truth.y - f[k].truth.y;
    const double c = std::cos(f[k].truth.theta), s = std::sin(f[k].truth.theta);
    v.push_back({(c * dx + s * dy) / dt, (-s * dx + c * dy) / dt, WrapAngle(f[k + 1].truth.theta - f[k].truth.theta) / dt});
  }
  return v;
}

// A robot told to stand still moves only by its slip: the velocities between its true
// poses are the Gauss-Markov process itself. Their spread and their correlation one
// frame apart (exp(-dt / tau)) are the model's, on every physics backend.
TEST(DrivingNoise, AStandingRobotSlipsWithTheModelsSpreadAndCorrelationOnEveryBackend) {
  const double tau = 0.2, dt = 1.0 / 30;
  const OmniModel model = Slipping(tau);
  for (const std::string& backend : AvailableOmniEngines()) {
    const std::vector<std::array<double, 3>> v = BodyVelocities(StandStill(backend, model, 240, 7));
    for (std::size_t c = 0; c < 3; ++c) {
      double sum2 = 0, lag1 = 0;
      for (std::size_t k = 0; k < v.size(); ++k) {
        sum2 += v[k][c] * v[k][c];
        if (k > 0) lag1 += v[k][c] * v[k - 1][c];
      }
      const double sd = std::sqrt(sum2 / v.size());
      // About 7200 frames, 1000 independent stretches of 2 tau: the spread within 10 %.
      EXPECT_NEAR(sd, model.driving_noise.sd[c], 0.1 * model.driving_noise.sd[c]) << backend << " axis " << c;
      EXPECT_NEAR(lag1 / sum2, std::exp(-dt / tau), 0.03) << backend << " axis " << c;
    }
  }
}

TEST(DrivingNoise, OffByDefaultDeterministicAndTheCamerasDrawsStayAsTheyWere) {
  OmniModel quiet = Slipping(0.15);
  quiet.driving_noise.simulated = false;
  const SimulationResult still = StandStill("analytic", quiet, 3, 4);
  for (const FrameRecord& f : still.frames[0]) EXPECT_EQ(f.truth.x, 0.0);
  EXPECT_EQ(testing::Omni4().driving_noise.simulated, false);

  const SimulationResult a = StandStill("analytic", Slipping(0.15), 3, 4);
  const SimulationResult b = StandStill("analytic", Slipping(0.15), 3, 4);
  const SimulationResult other = StandStill("analytic", Slipping(0.15), 3, 5);
  double moved = 0, differs = 0;
  for (std::size_t k = 0; k < a.frames[0].size(); ++k) {
    const FrameRecord &x = a.frames[0][k], &y = b.frames[0][k], &q = still.frames[0][k];
    EXPECT_EQ(x.truth.x, y.truth.x);
    EXPECT_EQ(x.truth.theta, y.truth.theta);
    moved = std::max(moved, std::hypot(x.truth.x, x.truth.y));
    differs = std::max(differs, std::abs(x.truth.x - other.frames[0][k].truth.x));
    // The camera's noise on the truth it captured D frames before: the same draws with
    // the slip as without it.
    const std::size_t d = static_cast<std::size_t>(quiet.vision_delay_frames);
    if (k >= d && x.observed && q.observed) {
      EXPECT_NEAR(x.seen.x - a.frames[0][k - d].truth.x, q.seen.x - still.frames[0][k - d].truth.x, 1e-12) << k;
      EXPECT_NEAR(x.seen.theta - a.frames[0][k - d].truth.theta, q.seen.theta - still.frames[0][k - d].truth.theta, 1e-12)
          << k;
    }
  }
  EXPECT_GT(moved, 0.005);  // m: it wandered
  EXPECT_GT(differs, 0.0);  // another seed, another wander
}

TEST(DrivingNoise, RestoringASavedStateSlipsTheSameWayAgain) {
  const OmniModel model = Slipping(0.15);
  FrameTiming timing;
  timing.frame_rate = 30;
  timing.physics_substeps = DefaultPhysicsSubsteps(30);
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{0, 0, 0}, nullptr});
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {model}, FieldModel{}, timing), 3);
  for (int k = 0; k < 10; ++k) sim.Step();
  const SimulationState saved = sim.Save();
  std::vector<Pose2> first, second;
  for (int k = 0; k < 20; ++k) first.push_back(sim.Step()[0].truth);
  sim.Restore(saved);
  for (int k = 0; k < 20; ++k) second.push_back(sim.Step()[0].truth);
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(first[k].x, second[k].x) << k;
    EXPECT_EQ(first[k].theta, second[k].theta) << k;
  }
  EXPECT_NE(first.front().x, first.back().x);
}

TEST(DrivingNoise, TheModelFileSaysWhetherItIsSimulated) {
  OmniModel m = Slipping(0.3);
  const std::string yaml = FormatOmniModelYaml(m);
  EXPECT_NE(yaml.find("simulated: true"), std::string::npos) << yaml;
  const OmniModel back = LoadOmniModelFromString(yaml, "back.yaml");
  EXPECT_TRUE(back.driving_noise.simulated);
  EXPECT_EQ(back.driving_noise.correlation_time, 0.3);
  EXPECT_THROW(LoadOmniModelFromString("driving_noise: {simulated: perhaps}\n", "bad.yaml"), InputError);
}

// `run --driving-noise on|off|model`: on, the 45 degree drive ends elsewhere, the same
// bytes for the same seed; off and model (the shipped model simulates none) agree; an arm
// scene refuses the option.
TEST(DrivingNoise, RunSwitchesItOnForEveryRobot) {
  const std::string dir = testing::TempDir("driving_noise_run");
  const std::string scene = testing::SourcePath("scenes/drive45.yaml");
  auto run = [&](const std::string& name, const std::string& option) {
    const testing::CommandResult r =
        testing::RunTwinsim("run " + scene + " --backend analytic -q --out " + dir + "/" + name + " " + option);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return testing::ReadText(dir + "/" + name + "/trajectory.csv");
  };
  const std::string on = run("on", "--driving-noise on");
  EXPECT_EQ(run("on_again", "--driving-noise on"), on);
  const std::string off = run("off", "--driving-noise off");
  EXPECT_NE(on, off);
  EXPECT_EQ(run("model", ""), off);
  const testing::CommandResult arm = testing::RunTwinsim("run " + testing::SourcePath("scenes/rrr_writing.yaml") +
                                                         " --driving-noise on -q --out " + dir + "/arm");
  EXPECT_EQ(arm.exit_code, 2) << arm.err;
  EXPECT_EQ(testing::RunTwinsim("run " + scene + " --driving-noise maybe --out " + dir + "/bad").exit_code, 2);
}

}  // namespace
}  // namespace twinsim
