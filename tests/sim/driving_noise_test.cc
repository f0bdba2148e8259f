// Driving noise drawn by the simulation loop (issue 42): with driving_noise.simulated the
// body slips by a first-order Gauss-Markov velocity per robot axis that the wheels and
// the controller never see, on every backend, from a random stream of its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "analysis/omni_replay.h"
#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "io/csv_table.h"
#include "render/renderer.h"
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

// A drift beside the slip (driving_noise.drift): a standing robot's body velocity,
// averaged over a second (where the fast slip, 10 ms long, averages out), follows the
// drift's slow process: its spread the drift's and its correlation a second apart
// exp(-1 / T_b), over many runs each drawn from its stationary spread at the start.
TEST(DrivingNoise, ADriftIsASlowSlipDrawnFromItsSpreadAtTheStart) {
  OmniModel model = Slipping(0.01);
  model.driving_noise.sd = {0.01, 0.01, 0.05};
  model.driving_noise.drift.sd = {0.04, 0.02, 0.2};
  model.driving_noise.drift.correlation_time = 4;
  std::array<double, 3> sum2{}, lag1{};
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const std::vector<std::array<double, 3>> v = BodyVelocities(StandStill("analytic", model, 6, seed));
    std::array<double, 3> first{}, second{};  // the means over the first two seconds
    for (std::size_t k = 0; k < 60; ++k) {
      for (std::size_t c = 0; c < 3; ++c) (k < 30 ? first : second)[c] += v[k][c] / 30;
    }
    for (std::size_t c = 0; c < 3; ++c) sum2[c] += first[c] * first[c], lag1[c] += first[c] * second[c];
    ++n;
  }
  for (std::size_t c = 0; c < 3; ++c) {
    // 40 runs: a spread within 25 % (its relative error about 1 / sqrt(2 * 40) = 11 %),
    // corrected for the second's average of a process of 4 s (about 0.98 of its spread)
    const double sd = std::sqrt(sum2[c] / n);
    EXPECT_NEAR(sd, model.driving_noise.drift.sd[c], 0.25 * model.driving_noise.drift.sd[c]) << "axis " << c;
    EXPECT_NEAR(lag1[c] / sum2[c], std::exp(-1.0 / 4), 0.15) << "axis " << c;
  }
}

// The body velocity's spread about its mean (forward, sideways, turn) while the robot
// drives `command` for 150 s, and that mean: the wheels' velocity is steady, so the
// spread is the slip's.
struct SteadySlip {
  std::array<double, 3> mean{}, spread{};
};
SteadySlip SlipWhileDriving(const OmniModel& model, const Twist2& command) {
  FrameTiming timing;
  timing.frame_rate = 30;
  timing.physics_substeps = DefaultPhysicsSubsteps(30);
  const double seconds = 150;
  CommandSpec steady;
  steady.type = "sequence";
  steady.segments = {{seconds, command, false}};
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{0, 0, 0}, MakeCommandSource(steady, 3, 0, seconds, Pose2{})});
  FieldModel open;
  open.walls = false;
  Simulation sim(std::move(robots), MakeOmniBackend("analytic", {model}, open, timing), 3);
  std::vector<std::array<double, 3>> v = BodyVelocities(sim.Run(static_cast<int>(seconds * 30)));
  v.erase(v.begin(), v.begin() + 60);  // the start's transient
  SteadySlip out;
  for (const auto& x : v)
    for (std::size_t c = 0; c < 3; ++c) out.mean[c] += x[c] / static_cast<double>(v.size());
  for (std::size_t c = 0; c < 3; ++c) {
    double sum2 = 0;
    for (const auto& x : v) sum2 += (x[c] - out.mean[c]) * (x[c] - out.mean[c]);
    out.spread[c] = std::sqrt(sum2 / static_cast<double>(v.size()));
  }
  return out;
}

// A spread that grows with speed (driving_noise.per_speed): a robot circling at about
// 0.8 m/s slips by sd (1 + per_speed v) on each axis.
TEST(DrivingNoise, ASpreadGrowingWithSpeedIsWiderWhileDriving) {
  OmniModel model = Slipping(0.1);
  model.driving_noise.per_speed = 1.5;
  const SteadySlip slip = SlipWhileDriving(model, Twist2{0.8, 0, 1.0});
  const double speed = std::hypot(slip.mean[0], slip.mean[1]);
  EXPECT_GT(speed, 0.5);
  for (std::size_t c = 0; c < 3; ++c) {
    const double expected = model.driving_noise.Spread(static_cast<int>(c), speed, 0, slip.mean[2]);
    // About 4400 frames, 700 independent stretches of 2 tau: within 10 %, and far from
    // the spread standing still (a factor 1 + 1.5 v, about 2).
    EXPECT_NEAR(slip.spread[c], expected, 0.1 * expected) << "axis " << c;
  }
}

// And with the turn rate (driving_noise.per_turn_rate): a robot spinning on the spot at
// about 3 rad/s slips by sd (1 + per_turn_rate |omega|), 2.5 times its spread standing,
// the same turning either way.
TEST(DrivingNoise, ASpreadGrowingWithTurnRateIsWiderWhileSpinning) {
  OmniModel model = Slipping(0.1);
  model.driving_noise.per_turn_rate = 0.5;
  for (double sign : {1.0, -1.0}) {
    const SteadySlip slip = SlipWhileDriving(model, Twist2{0, 0, 3 * sign});
    EXPECT_GT(sign * slip.mean[2], 2.0);
    EXPECT_LT(std::hypot(slip.mean[0], slip.mean[1]), 0.05);
    for (std::size_t c = 0; c < 3; ++c) {
      const double expected = model.driving_noise.Spread(static_cast<int>(c), 0, 0, slip.mean[2]);
      EXPECT_GT(expected, 2 * model.driving_noise.sd[c]);
      EXPECT_NEAR(slip.spread[c], expected, 0.1 * expected) << "axis " << c << " turning " << sign;
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
  EXPECT_EQ(back.driving_noise.per_speed, 0.0);
  EXPECT_EQ(yaml.find("per_speed"), std::string::npos) << yaml;
  m.driving_noise.per_speed = 0.75;
  m.driving_noise.per_acceleration = 0.125;
  const OmniModel grown = LoadOmniModelFromString(FormatOmniModelYaml(m), "grown.yaml");
  EXPECT_EQ(grown.driving_noise.per_speed, 0.75);
  EXPECT_EQ(grown.driving_noise.per_acceleration, 0.125);
  EXPECT_EQ(grown.driving_noise.per_turn_rate, 0.0);
  m.driving_noise.per_turn_rate = 0.375;
  const std::string turning = FormatOmniModelYaml(m);
  EXPECT_NE(turning.find("per_turn_rate: 0.375"), std::string::npos) << turning;
  EXPECT_EQ(LoadOmniModelFromString(turning, "turning.yaml").driving_noise.per_turn_rate, 0.375);
  EXPECT_THROW(LoadOmniModelFromString("driving_noise: {per_turn_rate: -0.5}\n", "bad.yaml"), InputError);
  EXPECT_THROW(LoadOmniModelFromString("driving_noise: {simulated: perhaps}\n", "bad.yaml"), InputError);
  EXPECT_THROW(LoadOmniModelFromString("driving_noise: {per_speed: -1}\n", "bad.yaml"), InputError);
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

// `run --samples N`: sample 0's files are the plain run's, samples.csv holds N rows per
// frame (t,sample,x,y,theta), the same bytes on one thread and two, the samples wander
// apart, and fan.png is drawn; refused (exit 2, nothing written) without driving noise,
// for --jobs alone and for an arm scene.
TEST(DrivingNoise, RunSamplesWritesSampleZeroAsAPlainRunAndTheFan) {
  const std::string dir = testing::TempDir("run_samples");
  const std::string scene = testing::SourcePath("scenes/drive45.yaml");
  auto run = [&](const std::string& name, const std::string& option) {
    return testing::RunTwinsim("run " + scene + " --backend analytic -q --out " + dir + "/" + name + " " + option);
  };
  ASSERT_EQ(run("plain", "--driving-noise on").exit_code, 0);
  ASSERT_EQ(run("one", "--driving-noise on --samples 20 --jobs 1").exit_code, 0);
  ASSERT_EQ(run("two", "--driving-noise on --samples 20 --jobs 2").exit_code, 0);
  EXPECT_EQ(testing::ReadText(dir + "/one/trajectory.csv"), testing::ReadText(dir + "/plain/trajectory.csv"));
  const std::string samples = testing::ReadText(dir + "/one/samples.csv");
  EXPECT_EQ(samples, testing::ReadText(dir + "/two/samples.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/one/fan.png") || !RenderingCompiled());
  const CsvTable table = ParseCsvTable(samples, "samples.csv");
  ASSERT_EQ(table.header, (std::vector<std::string>{"t", "sample", "x", "y", "theta"}));
  ASSERT_EQ(table.rows.size() % 20, 0u);
  // The last frame's 20 positions: apart by more than a centimetre.
  double mx = 0, my = 0;
  const std::size_t last = table.rows.size() - 20;
  for (std::size_t k = last; k < table.rows.size(); ++k) {
    EXPECT_EQ(table.rows[k][1], static_cast<double>(k - last));
    mx += table.rows[k][2] / 20, my += table.rows[k][3] / 20;
  }
  double spread = 0;
  for (std::size_t k = last; k < table.rows.size(); ++k)
    spread += (std::pow(table.rows[k][2] - mx, 2) + std::pow(table.rows[k][3] - my, 2)) / 20;
  EXPECT_GT(std::sqrt(spread), 0.01);
  for (const auto& [name, option] : std::vector<std::pair<std::string, std::string>>{
           {"quiet", "--driving-noise off --samples 5"}, {"jobs", "--driving-noise on --jobs 2"}}) {
    const testing::CommandResult r = run(name, option);
    EXPECT_EQ(r.exit_code, 2) << option << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/" + name)) << option;
  }
  EXPECT_EQ(testing::RunTwinsim("run " + testing::SourcePath("scenes/rrr_writing.yaml") + " --samples 3 -q --out " +
                                dir + "/arm")
                .exit_code,
            2);
}

// The contract's form: t,sample,x,y,theta, N rows per input row, sample 0..N-1, the same
// bytes for the same seed; refused (exit 2, nothing written) where it cannot apply.
TEST(DrivingNoise, ReplaySamplesWritesTheContractsColumns) {
  const std::string dir = testing::TempDir("replay_samples");
  ASSERT_EQ(testing::RunTwinsim("run " + testing::SourcePath("scenes/drive45.yaml") +
                                " --backend analytic --driving-noise on -q --out " + dir + "/run")
                .exit_code,
            0);
  const std::string model = testing::SourcePath("models/omni4.yaml"), log = dir + "/run/trajectory.csv";
  auto replay = [&](const std::string& out, const std::string& extra) {
    return testing::RunTwinsim("replay --model " + model + " --log " + log + " --backend analytic -q --out " + dir +
                               "/" + out + " " + extra);
  };
  ASSERT_EQ(replay("a.csv", "--samples 3 --seed 2").exit_code, 0);
  ASSERT_EQ(replay("b.csv", "--samples 3 --seed 2").exit_code, 0);
  ASSERT_EQ(replay("c.csv", "--samples 3 --seed 3").exit_code, 0);
  const std::string a = testing::ReadText(dir + "/a.csv");
  EXPECT_EQ(a, testing::ReadText(dir + "/b.csv"));
  EXPECT_NE(a, testing::ReadText(dir + "/c.csv"));
  const CsvTable table = ParseCsvTable(a, "a.csv");
  EXPECT_EQ(table.header, (std::vector<std::string>{"t", "sample", "x", "y", "theta"}));
  const CsvTable input = ReadCsvTable(log);
  ASSERT_EQ(table.rows.size(), 3 * input.rows.size());
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    EXPECT_EQ(table.rows[i][1], static_cast<double>(i % 3));
    EXPECT_EQ(table.rows[i][0], input.rows[i / 3][0]);
  }
  // The tracker's state draws rollouts under the model's driving noise instead (the
  // learned backend's way; analysis/learned_noise_test.cc).
  ASSERT_EQ(replay("tracker.csv", "--samples 3 --state tracker").exit_code, 0);
  EXPECT_EQ(ParseCsvTable(testing::ReadText(dir + "/tracker.csv"), "tracker.csv").rows.size(), 3 * input.rows.size());
  for (const char* bad : {"--samples 3 --horizon 0", "--samples -1"}) {
    EXPECT_EQ(replay("bad.csv", bad).exit_code, 2) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir + "/bad.csv")) << bad;
  }
}

// replay --samples: draws from the observer's prediction. On a plant that slips as its
// model says (the same driving noise simulated; the project's own plant, so this checks
// the sampling, not a model of another robot), the measured positions K frames ahead
// fall inside the samples' 50 % and 90 % circles (about their mean) about as often.
TEST(DrivingNoise, ReplaySamplesCoverTheMeasuredPositionsOfAPlantThatSlipsAsModelled) {
  OmniModel plant = testing::Omni4();
  plant.driving_noise.simulated = true;
  const OmniLog log = testing::RecordLog(plant, testing::RandomDrive(1.5, 3, 1.5), 90, 11, "analytic", "slipping.csv");
  for (int k : {4, 16, 63}) {
    OmniReplayOptions options;
    options.backend = "analytic";
    options.horizon = k;
    options.samples = 200;
    options.seed = 5;
    const OmniReplayResult r = ReplayOmniLog(testing::Omni4(), log, options);
    ASSERT_EQ(r.samples.size(), log.rows.size());
    int rows = 0, in50 = 0, in90 = 0;
    for (std::size_t i = 0; i < log.rows.size(); ++i) {
      ASSERT_EQ(r.samples[i].size(), 200u);
      if (!PredictedAndMeasured(log, r, i)) continue;
      double mx = 0, my = 0;
      for (const Pose2& p : r.samples[i]) mx += p.x / 200, my += p.y / 200;
      std::vector<double> d;
      for (const Pose2& p : r.samples[i]) d.push_back(std::hypot(p.x - mx, p.y - my));
      std::sort(d.begin(), d.end());
      const double measured = std::hypot(log.rows[i].pose.x - mx, log.rows[i].pose.y - my);
      ++rows;
      in50 += measured <= d[99];
      in90 += measured <= d[179];
    }
    // Measured (seed 11, 90 s at 30 fps): 52 / 91 % at 4 frames, 55 / 92 % at 16, 50 / 91 % at
    // 63; consecutive rows overlap, so a few percent either way is chance.
    EXPECT_GT(rows, 2500);
    EXPECT_NEAR(100.0 * in50 / rows, 50, 8) << "K " << k;
    EXPECT_NEAR(100.0 * in90 / rows, 90, 4) << "K " << k;
  }
}

}  // namespace
}  // namespace twinsim
