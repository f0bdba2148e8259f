// The protocol's synchronous interface over TCP (docs/serve.md "The synchronous
// interface"): requests written byte by byte from the official field numbers,
//   SimulationSyncRequest   sim_step = 1 (float, s), simulator_command = 2, robot_control = 3
//   SimulationSyncResponse  detection = 1 (repeated SSL_DetectionFrame), robot_control_response = 2
// each length-delimited (the length as a varint); the vision it answers is lockstep's,
// bit for bit, for the same commands.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <map>
#include <optional>
#include <thread>

#include "backends/omni_backend_factory.h"
#include "scene/scene.h"
#include "serve/live_field.h"
#include "serve/protobuf_wire.h"
#include "serve/tcp_stream.h"
#include "ssl_simulation_synchronous.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::BytesField;
using testing::FloatField;
using testing::SourcePath;
using testing::VarintField;

Scene SyncScene() {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  return LoadSceneFromString("name: sync\nbackend: analytic\nframe_rate: 60\nduration: 10\nseed: 9\n"
                             "ball: {start: {x: 1, y: 1}, vision: {noise_xy: 0.002, drop_probability: 0.1}}\nrobots:\n"
                             "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
                             "  - {name: y0, team: yellow, model: " + model + ", start: {x: 1, y: 0.5}, "
                             "commands: {type: random}}\n",
                             "sync.yaml", ".");
}

// Blue 0's move in frame k, as the RobotControl bytes of the official numbers:
// robot_commands(1) { id(1), move_command(2) { local_velocity(2) { forward(1), left(2), angular(3) } } }.
std::string BlueMove(int k) {
  const float v = k < 10 ? 0.0f : 0.8f, w = k < 10 ? 0.0f : 1.5f;
  return BytesField(1, VarintField(1, 0) + BytesField(2, BytesField(2, FloatField(1, v) + FloatField(2, 0.1f) +
                                                                          FloatField(3, w))));
}

ServeOptions Ports() {
  ServeOptions o;
  o.control_port = o.blue_port = o.yellow_port = 0;
  return o;
}

// Lockstep: the detection frame of each frame number, the client answering frame k
// with BlueMove(k).
std::map<std::uint32_t, std::string> Lockstep(int frames) {
  const Scene scene = SyncScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions o = Ports();
  o.vision_port = vision.port();
  o.lockstep = true;
  o.teams = {"blue"};
  o.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  std::thread server([&] { field.Run([] { return false; }); });
  std::map<std::uint32_t, std::string> seen;
  for (int tries = 0; tries < 2000 && seen.size() < static_cast<std::size_t>(frames); ++tries) {
    if (WaitReadable({&vision}, 0.05) < 0) continue;
    while (std::optional<Datagram> d = vision.Receive(65536)) {
      SSL_WrapperPacket p;
      if (!p.ParseFromString(d->bytes) || !p.has_detection()) continue;
      const std::uint32_t k = p.detection().frame_number();
      if (seen.count(k)) continue;  // sent again
      seen[k] = p.detection().SerializeAsString();
      client.SendTo(BlueMove(static_cast<int>(k)), UdpEndpoint{ParseIpv4("127.0.0.1"), field.blue_port()});
    }
  }
  server.join();
  return seen;
}

SimulationSyncResponse Ask(TcpConnection& c, const std::string& request) {
  EXPECT_TRUE(c.WriteMessage(request));
  SimulationSyncResponse r;
  for (int tries = 0; tries < 200; ++tries) {
    if (!WaitReadableFd(c.fd(), 0.05)) continue;
    c.ReadAvailable();
    if (std::optional<std::string> m = c.NextMessage(1 << 22)) {
      EXPECT_TRUE(r.ParseFromString(*m));
      return r;
    }
  }
  ADD_FAILURE() << "no response";
  return r;
}

TEST(SyncInterface, TheVisionIsLocksteps) {
  const int frames = 40;
  const std::map<std::uint32_t, std::string> lockstep = Lockstep(frames);
  ASSERT_EQ(lockstep.size(), static_cast<std::size_t>(frames));

  const Scene scene = SyncScene();
  ServeOptions o = Ports();
  o.sync_port = 0;
  o.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  ServeSummary summary;
  std::thread server([&] { summary = field.Run([] { return false; }); });
  TcpConnection c = TcpConnect("127.0.0.1", field.sync_port());
  // No step: the open frame's vision.
  SimulationSyncResponse r = Ask(c, "");
  ASSERT_EQ(r.detection_size(), 1);
  EXPECT_EQ(r.detection(0).SerializeAsString(), lockstep.at(0));
  const float dt = 1.0f / 60;
  for (int k = 0; k + 1 < frames; ++k) {
    r = Ask(c, FloatField(1, dt) + BytesField(3, BlueMove(k)));
    ASSERT_EQ(r.detection_size(), 1) << k;
    EXPECT_EQ(r.detection(0).frame_number(), static_cast<unsigned>(k + 1));
    EXPECT_EQ(r.detection(0).SerializeAsString(), lockstep.at(static_cast<std::uint32_t>(k + 1))) << "frame " << k + 1;
    ASSERT_EQ(r.robot_control_response().feedback_size(), 1);
    EXPECT_EQ(r.robot_control_response().errors_size(), 0);
  }
  // The last frame's step ends the field (--frames).
  Ask(c, FloatField(1, dt) + BytesField(3, BlueMove(frames - 1)));
  server.join();
  EXPECT_EQ(summary.counters.frames, frames);
  EXPECT_EQ(summary.counters.sync_requests, frames + 1);
  EXPECT_GT(field.result().frames[0].back().truth.x, 0.1) << "blue 0 should have driven";
}

TEST(SyncInterface, BadRequestsAreAnsweredAndABrokenStreamEndsOnlyItsConnection) {
  const Scene scene = SyncScene();
  ServeOptions o = Ports();
  o.sync_port = 0;
  o.max_frames = 12;
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  ServeSummary summary;
  std::thread server([&] { summary = field.Run([] { return false; }); });
  {
    TcpConnection c = TcpConnect("127.0.0.1", field.sync_port());
    auto codes = [](const SimulationSyncResponse& r) {
      std::vector<std::string> out;
      for (const SimulatorError& e : r.robot_control_response().errors()) out.push_back(e.code());
      return out;
    };
    EXPECT_EQ(codes(Ask(c, std::string("\xff\xff\xff", 3))), std::vector<std::string>{"TWINSIM_MALFORMED"});
    EXPECT_EQ(codes(Ask(c, FloatField(1, -1.0f))), std::vector<std::string>{"TWINSIM_BAD_VALUE"});
    // simulator_command(2) { control(1) { simulation_speed(3) 2 } }: the client sets the pace.
    EXPECT_EQ(codes(Ask(c, BytesField(2, BytesField(1, FloatField(3, 2.0f))))),
              std::vector<std::string>{"TWINSIM_UNSUPPORTED"});
    // simulator_command(2) { control(1) { teleport_robot(2) { id(1) { id(1) 0, team(2) BLUE=2 }, x(2) -1, y(3) -0.5 } } }
    const std::string teleport =
        BytesField(2, BytesField(1, BytesField(2, BytesField(1, VarintField(1, 0) + VarintField(2, 2)) +
                                                      FloatField(2, -1.0f) + FloatField(3, -0.5f))));
    const SimulationSyncResponse moved = Ask(c, teleport + FloatField(1, 0.1f));  // and 6 frames
    EXPECT_TRUE(codes(moved).empty());
    ASSERT_EQ(moved.detection_size(), 1);
    EXPECT_EQ(moved.detection(0).frame_number(), 6u);
    ASSERT_EQ(moved.detection(0).robots_blue_size(), 1);
    EXPECT_NEAR(moved.detection(0).robots_blue(0).x(), -1000, 10);  // seen after the 2 frames of vision delay
    // A length no request can have (2 GB): this connection is dropped.
    std::string huge;
    for (std::uint64_t v = std::uint64_t{1} << 31; v >= 0x80; v >>= 7) huge.push_back(static_cast<char>((v & 0x7f) | 0x80));
    huge.push_back(static_cast<char>((std::uint64_t{1} << 31) >> 28));
    ASSERT_EQ(::send(c.fd(), huge.data(), huge.size(), MSG_NOSIGNAL), static_cast<ssize_t>(huge.size()));
    // The server closes the connection: readable, and at its end.
    EXPECT_TRUE(WaitReadableFd(c.fd(), 5));
    EXPECT_FALSE(c.ReadAvailable()) << "the server should close the connection";
  }
  // A new client goes on where the field stood.
  TcpConnection again = TcpConnect("127.0.0.1", field.sync_port());
  const SimulationSyncResponse r = Ask(again, FloatField(1, 0.1f));
  ASSERT_EQ(r.detection_size(), 1);
  EXPECT_EQ(r.detection(0).frame_number(), 12u);
  server.join();
  EXPECT_EQ(summary.counters.frames, 12);
  EXPECT_EQ(summary.counters.malformed, 2);  // the garbage request and the broken stream
}

// Several cameras draw their noise once per frame: asking twice for the frame the field
// stands at (no step) gives the same bytes, and the next frame's vision does not depend
// on how often a client asked.
TEST(SyncInterface, AskingAgainForTheSameFrameGivesTheSameVision) {
  Scene scene = SyncScene();
  scene.cameras.emplace().grid = CameraGrid{2, 2, 0.4, 4};
  auto serve = [&](int asks) {
    ServeOptions o = Ports();
    o.sync_port = 0;
    o.max_frames = 3;
    LiveField field(scene, MakeSimulation(scene, "analytic"), o);
    std::thread server([&] { field.Run([] { return false; }); });
    TcpConnection c = TcpConnect("127.0.0.1", field.sync_port());
    std::vector<std::string> seen;
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < asks; ++a) seen.push_back(Ask(c, "").SerializeAsString());
      Ask(c, FloatField(1, 1.0f / 60) + BytesField(3, BlueMove(k)));
    }
    server.join();
    return seen;
  };
  const std::vector<std::string> once = serve(1), thrice = serve(3);
  ASSERT_EQ(thrice.size(), 9u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(thrice[static_cast<std::size_t>(3 * k)], thrice[static_cast<std::size_t>(3 * k + 2)]) << k;
    EXPECT_EQ(once[static_cast<std::size_t>(k)], thrice[static_cast<std::size_t>(3 * k)]) << k;
  }
  SimulationSyncResponse r;
  ASSERT_TRUE(r.ParseFromString(once[1]));
  EXPECT_EQ(r.detection_size(), 4);
}

// Messages split across reads, several in one read, and the length's varint in two.
TEST(TcpStream, MessagesAreFramedWhateverTheReadsCut) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  TcpConnection reader(fds[0]);
  const std::string big(300, 'b');  // its length takes two bytes: 0xac 0x02
  // "a" (length 1), big (length 300), an empty message, "cd" (length 2): 308 bytes.
  const std::string stream = std::string(1, '\x01') + "a" + std::string(1, '\xac') + std::string(1, '\x02') + big +
                             std::string(1, '\x00') + std::string(1, '\x02') + "cd";
  std::vector<std::string> got;
  std::size_t sent = 0;
  for (std::size_t cut : {std::size_t{2}, std::size_t{3}, std::size_t{100}, std::size_t{305}, stream.size()}) {
    if (cut > sent) {
      ASSERT_EQ(::write(fds[1], stream.data() + sent, cut - sent), static_cast<ssize_t>(cut - sent));
      sent = cut;
    }
    ASSERT_TRUE(reader.ReadAvailable());
    while (std::optional<std::string> m = reader.NextMessage(1000)) got.push_back(*m);
  }
  EXPECT_EQ(got, (std::vector<std::string>{"a", big, "", "cd"}));
  EXPECT_FALSE(reader.bad());
  ::close(fds[1]);
  EXPECT_FALSE(reader.ReadAvailable());  // closed by the peer
}

TEST(SyncInterface, OptionsAreChecked) {
  const Scene scene = SyncScene();
  ServeOptions o = Ports();
  o.sync_port = 0;
  o.lockstep = true;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--sync-port"), std::string::npos) << why;
  o.lockstep = false;
  o.sync_team = "green";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("green"), std::string::npos) << why;
  o.sync_team = "yellow";
  o.grsim_port = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--grsim-port"), std::string::npos) << why;
}

}  // namespace
}  // namespace twinsim
