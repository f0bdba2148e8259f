// grSim's own protocol on its own port (serve/grsim_packet.h, docs/serve.md "grSim's
// protocol"): packets written byte by byte from grSim's published field numbers, not
// from the project's generated code,
//   grSim_Packet            commands = 1, replacement = 2
//   grSim_Commands          timestamp = 1 (double), isteamyellow = 2, robot_commands = 3
//   grSim_Robot_Command     id = 1, kickspeedx = 2, kickspeedz = 3, triggermode = 4,
//                           veltangent = 5, velnormal = 6, velangular = 7, spinner = 8,
//                           wheelsspeed = 9, wheel1..wheel4 = 10..13 (floats)
//   grSim_Replacement       ball = 1, robots = 2
//   grSim_RobotReplacement  x = 1, y = 2, dir = 3 (doubles), id = 4, yellowteam = 5, turnon = 6
//   grSim_BallReplacement   x = 1, y = 2, vx = 3, vy = 4 (doubles)
// read into the league's messages, and served: a robot driven over grSim's port takes,
// bit for bit, the path it takes driven with the same velocities over its team's port.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "scene/scene.h"
#include "serve/grsim_packet.h"
#include "serve/live_field.h"
#include "serve/protobuf_wire.h"
#include "grSim_Robotstatus.pb.h"
#include "ssl_simulation_robot_feedback.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::BytesField;
using testing::DoubleField;
using testing::FloatField;
using testing::SourcePath;
using testing::VarintField;

// A grSim robot command: local velocities, or wheel speeds (rad/s) when `wheels`.
std::string GrSimCommand(unsigned id, float tangent, float normal, float angular, float kick_x = 0, float kick_z = 0,
                         bool spinner = false, const float* wheels = nullptr) {
  std::string c = VarintField(1, id) + FloatField(2, kick_x) + FloatField(3, kick_z) + FloatField(5, tangent) +
                  FloatField(6, normal) + FloatField(7, angular) + VarintField(8, spinner ? 1 : 0) +
                  VarintField(9, wheels ? 1 : 0);
  if (wheels)
    for (int k = 0; k < 4; ++k) c += FloatField(10 + k, wheels[k]);
  return c;
}

std::string GrSimCommands(bool yellow, const std::string& command) {
  return BytesField(1, DoubleField(1, 0.0) + VarintField(2, yellow ? 1 : 0) + BytesField(3, command));
}

std::string RobotReplacement(unsigned id, bool yellow, double x, double y, double dir_deg,
                             std::optional<bool> turnon = std::nullopt) {
  std::string r = DoubleField(1, x) + DoubleField(2, y) + DoubleField(3, dir_deg) + VarintField(4, id) +
                  VarintField(5, yellow ? 1 : 0);
  if (turnon) r += VarintField(6, *turnon ? 1 : 0);
  return BytesField(2, BytesField(2, r));  // grSim_Packet.replacement.robots
}

double NoWheels(TeamColor, unsigned) { return 0.03; }

TEST(GrSimPacket, CommandsBecomeTheLeaguesRobotControl) {
  const GrSimPacket read = ReadGrSimPacket(GrSimCommands(true, GrSimCommand(3, 1.5f, -0.5f, 2.0f, 3, 4, true)), NoWheels);
  ASSERT_TRUE(read.parsed);
  EXPECT_EQ(read.team, TeamColor::kYellow);
  ASSERT_TRUE(read.commands);
  EXPECT_FALSE(read.replacement);
  ASSERT_EQ(read.commands->robot_commands_size(), 1);
  const RobotCommand& c = read.commands->robot_commands(0);
  EXPECT_EQ(c.id(), 3u);
  ASSERT_TRUE(c.move_command().has_local_velocity());
  EXPECT_EQ(c.move_command().local_velocity().forward(), 1.5f);
  EXPECT_EQ(c.move_command().local_velocity().left(), -0.5f);
  EXPECT_EQ(c.move_command().local_velocity().angular(), 2.0f);
  EXPECT_FLOAT_EQ(c.kick_speed(), 5.0f);                                   // |(3, 4)|
  EXPECT_FLOAT_EQ(c.kick_angle(), static_cast<float>(std::atan2(4.0, 3.0) * 180 / kPi));  // 53.13 deg
  EXPECT_EQ(c.dribbler_speed(), static_cast<float>(kGrSimSpinnerRpm));
}

TEST(GrSimPacket, WheelSpeedsAreRimSpeedsOfTheRobotsOwnWheelsInTheProtocolsOrder) {
  const float wheels[4] = {10, 20, 30, 40};  // rad/s: grSim's wheels at 60, 135, 225, 300 deg
  const GrSimPacket read =
      ReadGrSimPacket(GrSimCommands(false, GrSimCommand(0, 9, 9, 9, 0, 0, false, wheels)), NoWheels);
  ASSERT_TRUE(read.commands);
  const RobotCommand& c = read.commands->robot_commands(0);
  ASSERT_TRUE(c.move_command().has_wheel_velocity()) << "wheelsspeed: the velocities are not used";
  const MoveWheelVelocity& w = c.move_command().wheel_velocity();
  EXPECT_FLOAT_EQ(w.front_left(), 0.3f);
  EXPECT_FLOAT_EQ(w.back_left(), 0.6f);
  EXPECT_FLOAT_EQ(w.back_right(), 0.9f);
  EXPECT_FLOAT_EQ(w.front_right(), 1.2f);
  EXPECT_EQ(c.kick_speed(), 0);
  EXPECT_EQ(c.dribbler_speed(), 0);
}

TEST(GrSimPacket, ReplacementBecomesTeleports) {
  const std::string ball = BytesField(2, BytesField(1, DoubleField(1, 0.5) + DoubleField(3, -1.0)));
  const GrSimPacket read =
      ReadGrSimPacket(RobotReplacement(2, true, 1.0, -0.5, 90) + RobotReplacement(1, false, 0, 0, 0, false) + ball,
                      NoWheels);
  ASSERT_TRUE(read.parsed);
  ASSERT_TRUE(read.replacement);
  const SimulatorControl& c = read.replacement->control();
  ASSERT_EQ(c.teleport_robot_size(), 2);
  const TeleportRobot& a = c.teleport_robot(0);
  EXPECT_EQ(a.id().id(), 2u);
  EXPECT_EQ(a.id().team(), YELLOW);
  EXPECT_FLOAT_EQ(a.x(), 1.0f);
  EXPECT_FLOAT_EQ(a.y(), -0.5f);
  EXPECT_FLOAT_EQ(a.orientation(), static_cast<float>(kPi / 2));
  EXPECT_TRUE(a.has_v_x() && a.v_x() == 0 && a.v_angular() == 0) << "grSim puts a robot down at rest";
  EXPECT_FALSE(a.has_present());
  const TeleportRobot& b = c.teleport_robot(1);
  EXPECT_EQ(b.id().team(), BLUE);
  ASSERT_TRUE(b.has_present());
  EXPECT_FALSE(b.present());
  ASSERT_TRUE(c.has_teleport_ball());
  EXPECT_FLOAT_EQ(c.teleport_ball().x(), 0.5f);
  EXPECT_FALSE(c.teleport_ball().has_y()) << "a coordinate left out is kept";
  EXPECT_FLOAT_EQ(c.teleport_ball().vx(), -1.0f);
  EXPECT_EQ(c.teleport_ball().vy(), 0.0f);
}

TEST(GrSimPacket, GarbageIsNotAPacketAndNeverThrows) {
  EXPECT_FALSE(ReadGrSimPacket(std::string("\xff\xff\xff\xff\xff", 5), NoWheels).parsed);
  EXPECT_FALSE(ReadGrSimPacket(BytesField(1, "\x0a\x05"), NoWheels).parsed);  // a length past the end
  const GrSimPacket empty = ReadGrSimPacket("", NoWheels);
  EXPECT_TRUE(empty.parsed);
  EXPECT_FALSE(empty.commands || empty.replacement);
}

// Blue 0 driving while yellow 3 stands, in lockstep; `options` say which port drives.
Scene GrSimScene() {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  return LoadSceneFromString("name: grsim\nbackend: analytic\nduration: 10\nseed: 5\n"
                             "ball: {start: {x: 2, y: 1}}\nrobots:\n"
                             "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
                             "  - {name: y3, team: yellow, id: 3, model: " + model +
                                 ", start: {x: 1, y: 0.5, theta_deg: 90}, " + hold + "}\n",
                             "grsim.yaml", ".");
}

UdpEndpoint ToLoopback(int port) { return UdpEndpoint{ParseIpv4("127.0.0.1"), port}; }

// `base` on free loopback ports with grSim's, vision to `vision`, in lockstep on blue's
// commands, for `frames` frames.
ServeOptions GrSimLockstep(ServeOptions base, const UdpSocket& vision, long long frames) {
  base.control_port = base.blue_port = base.yellow_port = 0;
  base.grsim_port = 0;
  base.vision_port = vision.port();
  base.lockstep = true;
  base.teams = {"blue"};
  base.max_frames = frames;
  return base;
}

// Waits for the vision of frame k on `vision`.
bool WaitForFrame(const UdpSocket& vision, std::uint32_t k) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < end) {
    if (std::optional<Datagram> d = vision.Receive(65536)) {
      SSL_WrapperPacket p;
      if (p.ParseFromString(d->bytes) && p.has_detection() && p.detection().frame_number() >= k) return true;
    } else {
      WaitReadable({&vision}, 0.05);
    }
  }
  return false;
}

// Serves `frames` lockstep frames; in frame k the client sends `packet(k)` to the port
// `port(field)` and, for lockstep, the blue team's answer comes from it.
SimulationResult ServeDriven(const ServeOptions& extra, const std::function<std::string(int)>& packet,
                             bool to_grsim, ServeSummary* summary = nullptr) {
  const Scene scene = GrSimScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  const ServeOptions options = GrSimLockstep(extra, vision, 30);
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  std::thread server([&] {
    const ServeSummary s = field.Run([] { return false; });
    if (summary) *summary = s;
  });
  for (int k = 0; k < 30; ++k) {
    EXPECT_TRUE(WaitForFrame(vision, static_cast<std::uint32_t>(k))) << k;
    client.SendTo(packet(k), ToLoopback(to_grsim ? field.grsim_port() : field.blue_port()));
  }
  server.join();
  return field.result();
}

TEST(GrSimPort, ARobotDrivenOverGrSimsPortTakesThePathOfTheLeaguesProtocol) {
  auto velocity = [](int k) { return k < 5 ? 0.0f : 0.8f; };
  const SimulationResult grsim = ServeDriven(
      ServeOptions{}, [&](int k) { return GrSimCommands(false, GrSimCommand(0, velocity(k), 0.2f, 1.0f)); }, true);
  const SimulationResult league = ServeDriven(
      ServeOptions{},
      [&](int k) {
        // RobotControl.robot_commands(1) { id(1), move_command(2) { local_velocity(2) { 1, 2, 3 } },
        // kick_speed(3) 0, kick_angle(4) 0, dribbler_speed(5) 0 }: what grSim's command translates to.
        const std::string local = FloatField(1, velocity(k)) + FloatField(2, 0.2f) + FloatField(3, 1.0f);
        return BytesField(1, VarintField(1, 0) + BytesField(2, BytesField(2, local)) + FloatField(3, 0) +
                                 FloatField(4, 0) + FloatField(5, 0));
      },
      false);
  ASSERT_EQ(grsim.frames[0].size(), 30u);
  ASSERT_EQ(league.frames[0].size(), 30u);
  for (std::size_t k = 0; k < 30; ++k) {
    EXPECT_EQ(grsim.frames[0][k].truth.x, league.frames[0][k].truth.x) << k;
    EXPECT_EQ(grsim.frames[0][k].truth.theta, league.frames[0][k].truth.theta) << k;
  }
  EXPECT_GT(grsim.frames[0].back().truth.x, 0.05) << "the robot should have moved";
}

TEST(GrSimPort, ReplacementTeleportsAndTournamentModeRefusesIt) {
  auto packet = [](int k) {
    std::string p = GrSimCommands(false, GrSimCommand(0, 0, 0, 0));
    if (k == 3) p += RobotReplacement(3, true, -1.0, -1.0, 180);
    return p;
  };
  ServeSummary open_summary, tournament_summary;
  const SimulationResult open = ServeDriven(ServeOptions{}, packet, true, &open_summary);
  ServeOptions tournament;
  tournament.tournament = true;
  const SimulationResult refused = ServeDriven(tournament, packet, true, &tournament_summary);
  // Yellow 3 is at (-1, -1) facing 180 deg from the frame after the replacement on.
  const FrameRecord& moved = open.frames[1].back();
  EXPECT_NEAR(moved.truth.x, -1.0, 1e-6);
  EXPECT_NEAR(moved.truth.y, -1.0, 1e-6);
  EXPECT_NEAR(std::abs(moved.truth.theta), kPi, 1e-6);
  EXPECT_EQ(open_summary.counters.grsim_packets, 30);
  EXPECT_EQ(open_summary.counters.refused, 0);
  const FrameRecord& stayed = refused.frames[1].back();
  EXPECT_NEAR(stayed.truth.x, 1.0, 1e-6);
  EXPECT_NEAR(stayed.truth.y, 0.5, 1e-6);
  EXPECT_EQ(tournament_summary.counters.refused, 1);
}

// Tournament mode: a team is driven from one address, over its own port or grSim's;
// another address commanding it over grSim's port is refused and moves nothing.
TEST(GrSimPort, TournamentModeKeepsATeamToTheAddressThatDrivesIt) {
  const Scene scene = GrSimScene();
  UdpSocket vision("127.0.0.1", 0), blue("127.0.0.1", 0), intruder("127.0.0.1", 0);
  ServeOptions o;
  o.tournament = true;
  o = GrSimLockstep(o, vision, 20);
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  ServeSummary summary;
  std::thread server([&] { summary = field.Run([] { return false; }); });
  // Blue 0 told to stand, over blue's port, from blue's address.
  const std::string stand = BytesField(
      1, VarintField(1, 0) + BytesField(2, BytesField(2, FloatField(1, 0) + FloatField(2, 0) + FloatField(3, 0))));
  ASSERT_TRUE(WaitForFrame(vision, 0));
  blue.SendTo(stand, ToLoopback(field.blue_port()));
  ASSERT_TRUE(WaitReadable({&blue}, 5) >= 0) << "no answer to blue's first command";
  {
    std::optional<Datagram> a = blue.Receive(65536);
    RobotControlResponse r;
    ASSERT_TRUE(a && r.ParseFromString(a->bytes));
    for (const SimulatorError& e : r.errors()) ADD_FAILURE() << e.code() << ": " << e.message();
  }
  for (int k = 1; k < 20; ++k) {
    ASSERT_TRUE(WaitForFrame(vision, static_cast<std::uint32_t>(k))) << k;
    intruder.SendTo(GrSimCommands(false, GrSimCommand(0, 1.5f, 0, 0)), ToLoopback(field.grsim_port()));
    blue.SendTo(stand, ToLoopback(field.blue_port()));
  }
  server.join();
  EXPECT_GE(summary.counters.grsim_packets, 15);
  EXPECT_EQ(summary.counters.refused, summary.counters.grsim_packets) << "every intruding packet refused";
  const Pose2& at = field.result().frames[0].back().truth;
  EXPECT_LT(std::hypot(at.x, at.y), 0.001) << "blue 0 was driven by the intruder";
}

// grSim's robot status (grSim_Robotstatus.proto: Robots_Status { repeated Robot_Status
// robots_status = 1 }, Robot_Status { robot_id = 1, infrared = 2, flat_kick = 3,
// chip_kick = 4 }), sent to the address blue's grSim packets come from at blue's status
// port: blue 0 drives onto a ball placed in front of it (infrared on), kicks it (a flat
// kick, the infrared off as the ball leaves), each change once; yellow, which sent
// nothing, hears nothing.
TEST(GrSimPort, RobotStatusSaysWhenTheBallIsAtTheDribblerAndWhenItIsKicked) {
  const Scene scene = GrSimScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0), yellow_status("127.0.0.1", 0);
  ServeOptions o;
  o.grsim_blue_status_port = client.port();
  o.grsim_yellow_status_port = yellow_status.port();
  o = GrSimLockstep(o, vision, 60);
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  std::thread server([&] { field.Run([] { return false; }); });
  // The ball 0.25 m ahead of blue 0 (at the origin, facing +x): grSim_Replacement.ball.
  const std::string place_ball = BytesField(2, BytesField(1, DoubleField(1, 0.25) + DoubleField(2, 0.0)));
  std::vector<Robots_Status> heard;
  int infrared_frame = -1, kick_frame = -1;
  for (int k = 0; k < 60; ++k) {
    ASSERT_TRUE(WaitForFrame(vision, static_cast<std::uint32_t>(k))) << k;
    while (std::optional<Datagram> d = client.Receive(65536)) {
      Robots_Status status;
      ASSERT_TRUE(status.ParseFromString(d->bytes));
      heard.push_back(status);
      for (const Robot_Status& r : status.robots_status()) {
        EXPECT_EQ(r.robot_id(), 0) << "only blue's robots";
        if (r.infrared() && infrared_frame < 0) infrared_frame = k;
        if (r.flat_kick()) kick_frame = k;
        EXPECT_FALSE(r.chip_kick());
      }
    }
    // Forward at 0.4 m/s until the ball is at the dribbler, then a 3 m/s flat kick.
    const bool kick = infrared_frame >= 0 && kick_frame < 0;
    std::string packet = GrSimCommands(false, GrSimCommand(0, infrared_frame < 0 ? 0.4f : 0.0f, 0, 0, kick ? 3.0f : 0.0f));
    if (k == 0) packet += place_ball;
    client.SendTo(packet, ToLoopback(field.grsim_port()));
  }
  server.join();
  ASSERT_GE(infrared_frame, 0) << "the ball never reached the dribbler";
  ASSERT_GT(kick_frame, infrared_frame) << "no flat kick reported";
  // The first status is every blue robot's (nothing was sent before), then one per change:
  // infrared on; the kick (and the ball gone); the kick over.
  ASSERT_GE(heard.size(), 3u);
  EXPECT_FALSE(heard.front().robots_status(0).infrared());
  int kicks = 0;
  for (const Robots_Status& s : heard) kicks += s.robots_status(0).flat_kick() ? 1 : 0;
  EXPECT_EQ(kicks, 1);
  EXPECT_FALSE(heard.back().robots_status(0).infrared());
  EXPECT_FALSE(heard.back().robots_status(0).flat_kick());
  EXPECT_FALSE(yellow_status.Receive(65536)) << "yellow sent no grSim packet";
}

}  // namespace
}  // namespace twinsim
