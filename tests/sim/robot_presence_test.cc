// Robots off the field and moves by force in the omni loop (sim/omni_simulation.h):
// a robot off the field is neither seen nor stepped nor touched, the others do not
// notice it, it comes back where it is added; a move by force arrives without a jump
// and collides on the way; presence and moves under way are saved and restored.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "engines/omni_engine.h"
#include "learning/omni_predictor.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

// Robot a drives forward from (-1, 1); robot b stands at the origin (or is off the
// field with `b_present` false), spinning slowly. Camera noise on: the noise streams
// are part of what must not change.
Scene TwoRobots(const std::string& backend, bool b_present, const std::string& ball = "", int frame_rate = 60) {
  const std::string model = SourcePath("models/omni4.yaml");
  return LoadSceneFromString(
      "name: presence\nbackend: " + backend + "\nframe_rate: " + std::to_string(frame_rate) +
      "\nduration: 10\nseed: 3\nrobots:\n"
      "  - {name: a, model: " + model + ", start: {x: -1, y: 1},"
      " commands: {type: sequence, segments: [{duration: 20, command: [0.5, 0, 0]}]}}\n"
      "  - {name: b, model: " + model + ", start: {x: 0, y: 0}, present: " + (b_present ? "true" : "false") +
          ", commands: {type: sequence, segments: [{duration: 20, command: [0, 0, 0.3]}]}}\n" + ball,
      "presence.yaml", ".");
}

std::vector<std::string> Backends() {
  std::vector<std::string> names = {"analytic"};
  for (const std::string& e : AvailableOmniEngines())
    if (e != "analytic") names.push_back(e);
  return names;
}

TEST(RobotPresence, ARobotOffTheFieldIsNeitherSeenNorSteppedAndTheOtherDoesNotNoticeIt) {
  for (const std::string& backend : Backends()) {
    SCOPED_TRACE(backend);
    Simulation with = MakeSimulation(TwoRobots(backend, true), backend);
    Simulation without = MakeSimulation(TwoRobots(backend, false), backend);
    EXPECT_TRUE(with.present(1));
    EXPECT_FALSE(without.present(1));
    const SimulationResult r_with = with.Run(90), r_without = without.Run(90);
    for (std::size_t k = 0; k < 90; ++k) {
      // Robot a: the same truth and the same camera noise, to the bit (its path never
      // comes near b's: b off the field takes no draw from the noise stream away).
      const FrameRecord& a1 = r_with.frames[0][k];
      const FrameRecord& a2 = r_without.frames[0][k];
      ASSERT_EQ(a1.truth.x, a2.truth.x) << k;
      ASSERT_EQ(a1.truth.theta, a2.truth.theta) << k;
      ASSERT_EQ(a1.observed, a2.observed) << k;
      ASSERT_EQ(a1.seen.x, a2.seen.x) << k;
      // Robot b off the field: never seen, sent nothing, held at its parking spot.
      const FrameRecord& b = r_without.frames[1][k];
      EXPECT_FALSE(b.present) << k;
      EXPECT_FALSE(b.observed) << k;
      EXPECT_EQ(b.command.omega, 0) << k;
      EXPECT_EQ(b.truth.x, Simulation::ParkedPose(1).x) << k;
      EXPECT_EQ(b.truth.y, Simulation::ParkedPose(1).y) << k;
      EXPECT_EQ(b.truth_velocity.omega, 0) << k;
      // On the field, b turns as commanded.
      EXPECT_TRUE(r_with.frames[1][k].present);
    }
    EXPECT_GT(std::abs(r_with.frames[1][89].truth.theta), 0.2);
  }
}

TEST(RobotPresence, OnTheLearnedBackendTooAParkedRobotIsHeldAndTheOtherDoesNotNoticeIt) {
  // A 1-frame predictor learned from 30 s of random driving at 30 fps (the rate
  // RecordLog logs at).
  const OmniModel m = testing::Omni4();
  const OmniLog drive = testing::RecordLog(m, testing::RandomDrive(2.0, 2.0, 2.0), 30, 5, "analytic", "drive.csv");
  OmniTrainOptions train;
  train.horizon = 1;
  OmniBackendOptions options;
  options.predictor = std::make_shared<OmniPredictor>(TrainOmniPredictor(m, {drive}, train));
  Simulation with = MakeSimulation(TwoRobots("learned", true, "", 30), "learned", options);
  Simulation without = MakeSimulation(TwoRobots("learned", false, "", 30), "learned", options);
  const SimulationResult r_with = with.Run(60), r_without = without.Run(60);
  for (std::size_t k = 0; k < 60; ++k) {
    ASSERT_EQ(r_with.frames[0][k].truth.x, r_without.frames[0][k].truth.x) << k;
    ASSERT_EQ(r_with.frames[0][k].seen.y, r_without.frames[0][k].seen.y) << k;
    const FrameRecord& b = r_without.frames[1][k];
    EXPECT_FALSE(b.observed) << k;
    EXPECT_EQ(b.truth.x, Simulation::ParkedPose(1).x) << k;
    EXPECT_EQ(b.truth.y, Simulation::ParkedPose(1).y) << k;
    EXPECT_EQ(b.truth.theta, 0) << k;
  }
  EXPECT_GT(r_with.frames[0][59].truth.x - r_with.frames[0][0].truth.x, 0.5);  // a drove on
}

TEST(RobotPresence, ItsLogsLeaveOutTheFramesOffTheField) {
  const Scene scene = TwoRobots("analytic", false);
  const SimulationResult r = RunOmniScene(scene, "analytic", "");
  const std::string dir = testing::TempDir("robot_presence_logs");
  OutputFiles files(dir);
  WriteOmniRunFiles(scene, r, false, &files);
  // b was off the field all run: its trajectory and truth are headers alone; a's have
  // every frame.
  const std::string truth_b = testing::ReadText(dir + "/truth_b.csv");
  EXPECT_EQ(truth_b, "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,vx,vy,omega\n");
  const std::string trajectory_b = testing::ReadText(dir + "/trajectory_b.csv");
  EXPECT_EQ(std::count(trajectory_b.begin(), trajectory_b.end(), '\n'), 1) << trajectory_b;
  const std::string truth_a = testing::ReadText(dir + "/truth.csv");
  EXPECT_EQ(std::count(truth_a.begin(), truth_a.end(), '\n'), static_cast<long>(r.frames[0].size()) + 1);
  EXPECT_EQ(TruePathLength(r, 1), 0);
}

TEST(RobotPresence, RemovedItLeavesVisionAfterTheCameraDelayAndAddedItComesBackWhereItIsPut) {
  for (const std::string& backend : Backends()) {
    SCOPED_TRACE(backend);
    Simulation sim = MakeSimulation(TwoRobots(backend, true), backend);
    const int delay = sim.robot_model(1).vision_delay_frames;
    ASSERT_EQ(delay, 2);
    std::vector<FrameRecord> b;
    const Pose2 put{1.5, -1, 0.5};
    for (int k = 0; k < 60; ++k) {
      std::vector<FrameRecord> r = sim.BeginFrame();
      for (int i = 0; i < 2; ++i)
        if (sim.present(i)) r[static_cast<std::size_t>(i)].command = sim.SourceCommand(i);
      if (k == 10) sim.Remove(1);
      if (k == 30) sim.Add(1, put, Twist2{});
      sim.EndFrame(&r);
      b.push_back(r[1]);
    }
    // Removed during frame 10 (captured at its start) and added during frame 30: on the
    // field in frames 0..10 and from 31; seen until the last capture has come through
    // the camera's delay (frame 12 delivers frame 10's), and again from the first
    // capture after the add (frame 31's, delivered at 33).
    for (int k = 0; k < 60; ++k) {
      const bool seen = k <= 10 + delay || k >= 31 + delay;
      EXPECT_EQ(b[static_cast<std::size_t>(k)].observed, seen) << k;
      EXPECT_EQ(b[static_cast<std::size_t>(k)].present, k <= 10 || k >= 31) << k;
    }
    // Added at `put`, at rest: seen there (noise 1 mm), then it turns as commanded.
    EXPECT_NEAR(b[33].seen.x, put.x, 0.005);
    EXPECT_NEAR(b[33].seen.y, put.y, 0.005);
    EXPECT_NEAR(b[31].truth.theta, put.theta, 0.02);
    EXPECT_GT(b[59].truth.theta - put.theta, 0.05);
    // Removing twice is nothing; teleporting or pulling a robot off the field is refused.
    sim.Remove(0);
    sim.Remove(0);
    EXPECT_FALSE(sim.present(0));
    EXPECT_THROW(sim.Teleport(0, Pose2{}, Twist2{}), std::logic_error);
    EXPECT_THROW(sim.PullRobot(0, Pose2{}), std::logic_error);
  }
}

TEST(RobotPresence, TheBallRollsThroughWhereARobotOffTheFieldWouldStand) {
  // The ball rolls at 2 m/s along y = 0 through b's start at the origin.
  const std::string ball = "ball: {start: {x: -0.6, y: 0, vx: 2}}\n";
  for (bool b_present : {true, false}) {
    SCOPED_TRACE(b_present);
    Simulation sim = MakeSimulation(TwoRobots("ode", b_present, ball), "ode");
    sim.Run(45);
    const BallState& end = sim.ball()->ball();
    if (b_present) {
      EXPECT_LT(end.position.x(), 0);  // stopped and thrown back by b's chassis
    } else {
      EXPECT_GT(end.position.x(), 0.3);  // straight through
      EXPECT_NEAR(end.position.y(), 0, 1e-9);
      EXPECT_FALSE(sim.ball()->contact(1));
    }
  }
}

TEST(RobotPresence, SaveAndRestoreBringBackWhoIsOnTheFieldAndMovesUnderWay) {
  for (const std::string& backend : Backends()) {
    SCOPED_TRACE(backend);
    Simulation sim = MakeSimulation(TwoRobots(backend, true, "ball: {start: {x: 1, y: -1}}\n"), backend);
    sim.Run(5);
    sim.Remove(1);
    sim.PullRobot(0, Pose2{0, 1.5, 1.0});
    sim.PullBall(Eigen::Vector2d(-1, -1));
    const SimulationState saved = sim.Save();
    const SimulationResult first = sim.Run(40);
    sim.Add(1, Pose2{2, 2, 0}, Twist2{});
    sim.Restore(saved);
    EXPECT_FALSE(sim.present(1));
    ASSERT_TRUE(sim.pull(0).has_value());
    ASSERT_TRUE(sim.ball()->pull().has_value());
    const SimulationResult second = sim.Run(40);
    // Bit for bit, except on ODE, whose API re-normalises a restored quaternion
    // (tests/sim/save_restore_test.cc): below a nanometre.
    const double tolerance = backend == "ode" ? 1e-9 : 0.0;
    for (std::size_t k = 0; k < 40; ++k) {
      for (std::size_t i = 0; i < 2; ++i) {
        ASSERT_NEAR(first.frames[i][k].truth.x, second.frames[i][k].truth.x, tolerance) << i << " " << k;
        ASSERT_EQ(first.frames[i][k].present, second.frames[i][k].present) << i << " " << k;
        ASSERT_NEAR(first.frames[i][k].seen.y, second.frames[i][k].seen.y, tolerance) << i << " " << k;
      }
      ASSERT_NEAR(first.ball[k].truth.position.x(), second.ball[k].truth.position.x(), tolerance) << k;
    }
    // The robot was pulled, and b stayed off the field until the end.
    EXPECT_GT(std::abs(first.frames[0][39].truth.y - first.frames[0][0].truth.y), 0.3);
    EXPECT_FALSE(first.frames[1][39].present);
  }
}

// Pulls robot a by force to `target` and checks every frame: the path is continuous,
// the speed bounded, and it arrives. Returns the frames it took.
int PullAndCheck(Simulation* sim, const Pose2& target, int max_frames) {
  sim->PullRobot(0, target);
  const double dt = sim->backend().timing().frame_dt();
  Pose2 last = sim->backend().pose(0);
  int frames = 0;
  // The pull lets go at the start of a frame's step, when the robot is there: the pose
  // before that step is the one to check.
  Pose2 let_go = last;
  while (sim->pull(0) && frames < max_frames) {
    let_go = last;
    sim->Step();
    ++frames;
    const Pose2 now = sim->backend().pose(0);
    // No jump: at most the pull's speed (10 % over for the controller's overshoot).
    EXPECT_LE(std::hypot(now.x - last.x, now.y - last.y), 1.1 * Simulation::kPullSpeed * dt) << frames;
    EXPECT_LE(std::abs(WrapAngle(now.theta - last.theta)), 1.1 * Simulation::kPullOmega * dt) << frames;
    const Twist2 v = sim->backend().velocity(0);
    EXPECT_LE(std::hypot(v.vx, v.vy), 1.1 * Simulation::kPullSpeed) << frames;
    last = now;
  }
  EXPECT_FALSE(sim->pull(0).has_value()) << "not there after " << frames << " frames";
  EXPECT_LT(std::hypot(let_go.x - target.x, let_go.y - target.y), Simulation::kPullTolerance);
  EXPECT_LT(std::abs(WrapAngle(let_go.theta - target.theta)), Simulation::kPullAngleTolerance);
  return frames;
}

TEST(RobotPresence, AMoveByForceArrivesWithoutAJump) {
  for (const std::string& backend : Backends()) {
    SCOPED_TRACE(backend);
    Simulation sim = MakeSimulation(TwoRobots(backend, false), backend);
    sim.Run(5);
    // 2.5 m and a quarter turn: about 1.25 s at 2 m/s, plus the braking and the settling.
    const int frames = PullAndCheck(&sim, Pose2{1.5, -1, 1.6}, 600);
    EXPECT_GT(frames, 60);
    EXPECT_LT(frames, 300);
    // Let go, the robot follows its own commands again (0.5 m/s forward).
    sim.Run(30);
    EXPECT_GT(sim.backend().velocity(0).vx, 0.3);
  }
}

TEST(RobotPresence, AMoveByForceCollidesOnTheWay) {
  // Robot a is pulled through the origin, where b stands: on the engines with contacts
  // b is pushed away (on the analytic backend, without contacts between robots, it is not).
  for (const std::string& backend : Backends()) {
    if (backend == "analytic") continue;
    SCOPED_TRACE(backend);
    Simulation sim = MakeSimulation(TwoRobots(backend, true), backend);
    sim.PullRobot(0, Pose2{1, -1, 0});
    double pushed = 0;
    for (int k = 0; k < 120; ++k) {
      sim.Step();
      const Pose2 b = sim.backend().pose(1);
      pushed = std::max(pushed, std::hypot(b.x, b.y));
    }
    EXPECT_GT(pushed, 0.05);
  }
}

TEST(RobotPresence, TheBallMovedByForceArrivesWithoutAJumpAndIsLetGo) {
  Simulation sim = MakeSimulation(TwoRobots("analytic", false, "ball: {start: {x: 1, y: -1}}\n"), "analytic");
  const Eigen::Vector2d target(-0.5, 1.5);
  sim.PullBall(target);
  const double dt = sim.backend().timing().frame_dt();
  Eigen::Vector3d last = sim.ball()->ball().position;
  int frames = 0;
  double fastest = 0;
  while (sim.ball()->pull() && frames < 600) {
    sim.Step();
    ++frames;
    const BallState& b = sim.ball()->ball();
    EXPECT_LE((b.position - last).norm(), 1.1 * BallField::kPullSpeed * dt) << frames;
    fastest = std::max(fastest, b.velocity.norm());
    last = b.position;
  }
  EXPECT_FALSE(sim.ball()->pull().has_value());
  EXPECT_GT(fastest, 0.9 * BallField::kPullSpeed);  // it did travel at the pull's speed
  EXPECT_LE(fastest, 1.1 * BallField::kPullSpeed);
  // 2.9 m: about 1.5 s at 2 m/s and the spring's settling.
  EXPECT_GT(frames, 60);
  EXPECT_LT(frames, 240);
  EXPECT_LT((sim.ball()->ball().position.head<2>() - target).norm(), BallField::kPullTolerance);
  // Let go at under 2 cm/s: it stays there.
  sim.Run(60);
  EXPECT_LT((sim.ball()->ball().position.head<2>() - target).norm(), 0.02);
  // A teleport ends a move by force.
  sim.PullBall(Eigen::Vector2d(0, 0));
  sim.TeleportBall(sim.ball()->ball());
  EXPECT_FALSE(sim.ball()->pull().has_value());
}

}  // namespace
}  // namespace twinsim
