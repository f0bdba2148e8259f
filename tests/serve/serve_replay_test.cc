// A match served in lockstep and the same match replayed by `twinsim run --commands`
// (scene/command_log.h): the client's vision stream holds exactly the poses `run`'s
// observer logs, and every file the two write is the same, byte for byte. On ODE with the
// ball, camera noise and lost frames; one robot driven by local velocities, kicks and the
// dribbler, the other by its scene's script and then by global velocities.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "io/output_files.h"
#include "scene/command_log.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "serve/live_field.h"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;
using testing::SourcePath;

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// Blue 0 at the ball, yellow 3 on a seeded random drive; the camera loses a tenth of
// the frames.
Scene MatchScene(const std::string& dir) {
  WriteText(dir + "/m.yaml", "extends: " + SourcePath("models/omni4.yaml") + "\nvision: {drop_probability: 0.1}\n");
  const double front = testing::Omni4().FrontDistance() + BallModel{}.radius;
  WriteText(dir + "/match.yaml",
            "name: match\nbackend: ode\nframe_rate: 60\nduration: 30\nseed: 11\nrobots:\n"
            "  - {name: b0, model: m.yaml, start: {x: 0, y: 0},\n"
            "     commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}}\n"
            "  - {name: y3, team: yellow, id: 3, model: m.yaml, start: {x: 1, y: 1.5, theta_deg: 90},\n"
            "     commands: {type: random, max_speed: 1, leash: 0.5}}\n"
            "ball: {start: {x: " + std::to_string(front) + ", y: 0}}\n");
  return LoadScene(dir + "/match.yaml");
}

// What the blue client sends in answer to frame k: a dribble, a turn, a kick, a drive.
std::string BlueAt(int k) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(0);
  MoveLocalVelocity* v = c->mutable_move_command()->mutable_local_velocity();
  v->set_forward(k < 20 ? 0.0f : 0.7f);
  v->set_left(k < 20 ? 0.0f : 0.3f * std::sin(0.1f * static_cast<float>(k)));
  v->set_angular(k < 10 ? 0.5f : -0.25f);
  if (k < 15) c->set_dribbler_speed(800);
  if (k == 15) {
    c->set_kick_speed(4);
    c->set_kick_angle(30);
  }
  return control.SerializeAsString();
}

// What the yellow client sends from frame 25 on: global velocities.
std::string YellowAt(int k) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(3);
  MoveGlobalVelocity* g = c->mutable_move_command()->mutable_global_velocity();
  g->set_vel_x(-0.5f);
  g->set_vel_y(0.2f * std::cos(0.05f * static_cast<float>(k)));
  g->set_vel_angular(1.0f);
  return control.SerializeAsString();
}

std::optional<std::string> ReceiveOne(const UdpSocket& socket) {
  for (int tries = 0; tries < 100; ++tries) {
    if (auto d = socket.Receive(65536)) return d->bytes;
    WaitReadable({&socket}, 0.05);
  }
  return std::nullopt;
}

TEST(ServeReplay, ALockstepMatchReplayedByRunGivesTheClientsVisionAndTheSameFiles) {
  const std::string dir = testing::TempDir("serve_replay");
  const Scene scene = MatchScene(dir);
  const int frames = 90;
  UdpSocket vision("127.0.0.1", 0), blue("127.0.0.1", 0), yellow("127.0.0.1", 0);
  ServeOptions options;
  options.control_port = options.blue_port = options.yellow_port = 0;
  options.vision_port = vision.port();
  options.lockstep = true;
  options.teams = {"blue"};
  options.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, "ode"), options);

  std::vector<SSL_DetectionFrame> seen;
  std::thread server([&] { field.Run([] { return false; }); });
  for (int k = 0; k < frames; ++k) {
    std::optional<SSL_DetectionFrame> frame;
    while (!frame) {
      std::optional<std::string> bytes = ReceiveOne(vision);
      ASSERT_TRUE(bytes) << "no vision for frame " << k;
      SSL_WrapperPacket p;
      if (p.ParseFromString(*bytes) && p.has_detection() && p.detection().frame_number() == static_cast<std::uint32_t>(k))
        frame = p.detection();
    }
    seen.push_back(*frame);
    // Yellow joins at frame 25 (from then on lockstep waits for it too); both answer.
    if (k >= 25) {
      ASSERT_TRUE(yellow.SendTo(YellowAt(k), UdpEndpoint{ParseIpv4("127.0.0.1"), field.yellow_port()}));
    }
    ASSERT_TRUE(blue.SendTo(BlueAt(k), UdpEndpoint{ParseIpv4("127.0.0.1"), field.blue_port()}));
    ASSERT_TRUE(ReceiveOne(blue)) << k;
    if (k >= 25) {
      ASSERT_TRUE(ReceiveOne(yellow)) << k;
    }
  }
  server.join();

  // What `twinsim serve` writes at Ctrl-C, and what `twinsim run --commands` writes.
  OutputFiles served(dir + "/served");
  WriteOmniRunFiles(scene, field.result(), /*plots=*/false, &served);
  served.Write("commands.csv", CommandsCsv(field.result()));
  Scene replay = MatchScene(dir);
  ReplayCommandLog(dir + "/served/commands.csv", &replay);
  ASSERT_EQ(replay.num_frames(), frames);
  const SimulationResult run = RunOmniScene(replay, "ode", "");
  OutputFiles ran(dir + "/ran");
  WriteOmniRunFiles(replay, run, /*plots=*/false, &ran);

  for (const char* name : {"trajectory.csv", "trajectory_y3.csv", "truth.csv", "truth_y3.csv", "ball.csv"}) {
    const std::string a = ReadAll(served.Path(name)), b = ReadAll(ran.Path(name));
    EXPECT_FALSE(a.empty()) << name;
    EXPECT_TRUE(a == b) << name << " differs between serve and run";
  }

  // The client saw run's observer: each robot's pose in mm and rad, as floats, in the
  // frames the camera did not lose; the ball where run's camera delivered it.
  int lost = 0, kicked = 0;
  for (int k = 0; k < frames; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    const SSL_DetectionFrame& f = seen[ku];
    const FrameRecord& b0 = run.frames[0][ku];
    const FrameRecord& y3 = run.frames[1][ku];
    ASSERT_EQ(f.robots_blue_size(), b0.observed ? 1 : 0) << k;
    ASSERT_EQ(f.robots_yellow_size(), y3.observed ? 1 : 0) << k;
    lost += !b0.observed + !y3.observed;
    if (b0.observed) {
      EXPECT_EQ(f.robots_blue(0).x(), static_cast<float>(1000 * b0.seen.x)) << k;
      EXPECT_EQ(f.robots_blue(0).y(), static_cast<float>(1000 * b0.seen.y)) << k;
      EXPECT_EQ(f.robots_blue(0).orientation(), static_cast<float>(b0.seen.theta)) << k;
    }
    if (y3.observed) {
      EXPECT_EQ(f.robots_yellow(0).x(), static_cast<float>(1000 * y3.seen.x)) << k;
      EXPECT_EQ(f.robots_yellow(0).orientation(), static_cast<float>(y3.seen.theta)) << k;
    }
    const BallRecord& ball = run.ball[ku];
    ASSERT_EQ(f.balls_size(), ball.observed ? 1 : 0) << k;
    if (ball.observed) {
      EXPECT_EQ(f.balls(0).x(), static_cast<float>(1000 * ball.seen.x())) << k;
      EXPECT_EQ(f.balls(0).z(), static_cast<float>(1000 * ball.seen.z())) << k;
    }
    kicked += run.frames[0][ku].ball_command.kick_speed > 0;
  }
  // The match had what it should: lost frames, one chip, the ball in the air after it.
  EXPECT_GT(lost, 5);
  EXPECT_EQ(kicked, 1);
  double apex = 0;
  for (const BallRecord& b : run.ball) apex = std::max(apex, b.truth.position.z());
  EXPECT_GT(apex, 0.1);
}

TEST(ServeReplay, ACommandLogReadsBackTheSameDoublesAndHoldsBetweenRows) {
  const std::string dir = testing::TempDir("command_log");
  SimulationResult result;
  result.robot_names = {"a", "b"};
  result.timing.frame_rate = 60;
  result.frames.resize(2);
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 2; ++i) {
      FrameRecord f;
      f.t = k / 60.0;
      f.command = Twist2{0.1 * (k + 1) / 3.0, -std::sqrt(2.0) / (i + 1), std::nextafter(1.0, 2.0)};
      if (k == 1) f.ball_command = BallCommand{4.0 / 3.0, 0.5235987755982988, 800};
      result.frames[static_cast<std::size_t>(i)].push_back(f);
    }
  }
  // A robot added to the field at frame 1 (off it in frame 0), and one whose records
  // begin later: rows only where it was on the field.
  result.robot_names.push_back("late");
  result.frames.push_back(result.frames[0]);
  result.frames.back()[0].present = false;
  result.robot_names.push_back("later");
  result.frames.push_back({result.frames[0][2]});
  WriteText(dir + "/c.csv", CommandsCsv(result));
  EXPECT_EQ(ReadCommandLog(dir + "/c.csv", "late", 60).frames, (std::vector<int>{1, 2}));
  EXPECT_EQ(ReadCommandLog(dir + "/c.csv", "later", 60).frames, (std::vector<int>{2}));
  const CommandLog log = ReadCommandLog(dir + "/c.csv", "b", 60);
  ASSERT_EQ(log.frames, (std::vector<int>{0, 1, 2}));
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(log.moves[k].vx, result.frames[1][k].command.vx);
    EXPECT_EQ(log.moves[k].vy, result.frames[1][k].command.vy);
    EXPECT_EQ(log.moves[k].omega, result.frames[1][k].command.omega);
  }
  EXPECT_EQ(log.balls[1].kick_speed, 4.0 / 3.0);

  // A log with gaps (the contract's log, lost frames left out): the last row holds; a
  // kick acts only in its own frame; zero before the first row.
  WriteText(dir + "/gaps.csv", "t,vx_cmd,vy_cmd,omega_cmd,kick_speed\n0.1,1,0,0,0\n0.2,2,0,0,3\n");
  LogCommandSource source(std::make_shared<CommandLog>(ReadCommandLog(dir + "/gaps.csv", "any", 30)));
  std::vector<Observation> none;
  auto at = [&](int frame) {
    BehaviourInput in;
    in.frame = frame;
    in.observations = &none;
    return std::make_pair(source.Command(in).vx, source.Ball(in).kick_speed);
  };
  EXPECT_EQ(at(2), std::make_pair(0.0, 0.0));
  EXPECT_EQ(at(3), std::make_pair(1.0, 0.0));
  EXPECT_EQ(at(5), std::make_pair(1.0, 0.0));
  EXPECT_EQ(at(6), std::make_pair(2.0, 3.0));
  EXPECT_EQ(at(7), std::make_pair(2.0, 0.0));
  EXPECT_EQ(at(1000), std::make_pair(2.0, 0.0));
}

}  // namespace
}  // namespace twinsim
