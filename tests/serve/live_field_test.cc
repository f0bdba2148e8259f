// A served field on the loopback (127.0.0.1, ports the system picks, never multicast):
// lockstep equals the simulation with the same commands, a command shows in vision
// at k + D + 1, and every refusal is answered and counted.
#include "serve/live_field.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>
#include <thread>

#include "backends/omni_backend_factory.h"
#include "scene/scene.h"
#include "ssl_simulation_custom_erforce_realism.pb.h"
#include "ssl_simulation_control.pb.h"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

// Blue 0 and yellow 3 on the analytic backend; both follow zero commands unless a
// client drives them.
Scene TwoTeamScene() {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  return LoadSceneFromString("name: served\nbackend: analytic\nduration: 10\nseed: 7\nrobots:\n"
                             "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
                             "  - {name: y3, team: yellow, id: 3, model: " + model +
                                 ", start: {x: 1, y: 0.5, theta_deg: 90}, " + hold + "}\n",
                             "served.yaml", ".");
}

ServeOptions LoopbackOptions(int vision_port) {
  ServeOptions o;
  o.control_port = o.blue_port = o.yellow_port = 0;
  o.vision_port = vision_port;
  return o;
}

// Lockstep waiting for the blue team from frame 0, for `frames` frames.
ServeOptions LockstepOptions(int vision_port, int frames) {
  ServeOptions o = LoopbackOptions(vision_port);
  o.lockstep = true;
  o.teams = {"blue"};
  o.max_frames = frames;
  return o;
}

// Runs the field on a thread until Stop() (or its frame limit).
class ServerThread {
 public:
  explicit ServerThread(LiveField* field) : field_(field) {
    thread_ = std::thread([this] { summary_ = field_->Run([this] { return stop_.load(); }); });
  }
  ~ServerThread() { Stop(); }
  const ServeSummary& Stop() {
    stop_ = true;
    return Join();
  }
  // Waits for the field to end by itself (its frame limit).
  const ServeSummary& Join() {
    if (thread_.joinable()) thread_.join();
    return summary_;
  }

 private:
  LiveField* field_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  ServeSummary summary_;
};

// The next datagram on `socket` within `timeout` s.
std::optional<std::string> Receive(const UdpSocket& socket, double timeout = 5) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout);
  while (std::chrono::steady_clock::now() < end) {
    if (auto d = socket.Receive(65536)) return d->bytes;
    WaitReadable({&socket}, 0.05);
  }
  return std::nullopt;
}

// The next detection frame numbered at least `frame`.
std::optional<SSL_DetectionFrame> ReceiveFrame(const UdpSocket& vision, std::uint32_t frame) {
  for (int tries = 0; tries < 100; ++tries) {
    std::optional<std::string> bytes = Receive(vision);
    if (!bytes) return std::nullopt;
    SSL_WrapperPacket p;
    if (p.ParseFromString(*bytes) && p.has_detection() && p.detection().frame_number() >= frame) return p.detection();
  }
  return std::nullopt;
}

UdpEndpoint Loopback(int port) { return UdpEndpoint{ParseIpv4("127.0.0.1"), port}; }

std::string Local(unsigned id, const Twist2& v) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(id);
  MoveLocalVelocity* m = c->mutable_move_command()->mutable_local_velocity();
  m->set_forward(static_cast<float>(v.vx));
  m->set_left(static_cast<float>(v.vy));
  m->set_angular(static_cast<float>(v.omega));
  return control.SerializeAsString();
}

// Sends `bytes` from `client` to the loopback `port` and reads the answer as a Response.
template <typename Response>
std::optional<Response> Ask(const UdpSocket& client, const std::string& bytes, int port) {
  if (!client.SendTo(bytes, Loopback(port))) return std::nullopt;
  std::optional<std::string> answer = Receive(client);
  Response r;
  if (!answer || !r.ParseFromString(*answer)) return std::nullopt;
  return r;
}

// A SimulatorCommand that puts blue robot 0 at (x, y).
std::string TeleportBlue0(float x, float y) {
  SimulatorCommand command;
  TeleportRobot* t = command.mutable_control()->add_teleport_robot();
  t->mutable_id()->set_id(0);
  t->mutable_id()->set_team(BLUE);
  t->set_x(x);
  t->set_y(y);
  return command.SerializeAsString();
}

// The error codes of a response, in order.
template <typename Response>
std::vector<std::string> Codes(const std::optional<Response>& r) {
  std::vector<std::string> codes;
  if (!r) return {"no answer"};
  for (const SimulatorError& e : r->errors()) codes.push_back(e.code());
  return codes;
}
using Codes1 = std::vector<std::string>;

// The blue robot's command at frame k: still until frame 10, then forward and turning.
Twist2 CommandAt(int k) { return k < 10 ? Twist2{} : Twist2{1.0, 0.25, 1.0}; }

TEST(LiveField, LockstepVisionIsTheSimulationsAndACommandShowsAtKPlusDelayPlusOne) {
  const Scene scene = TwoTeamScene();
  const int frames = 30;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  const ServeOptions options = LockstepOptions(vision.port(), frames);
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);

  std::vector<SSL_DetectionFrame> seen;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      ASSERT_EQ(f->frame_number(), static_cast<std::uint32_t>(k));
      seen.push_back(*f);
      // Floats on the wire: the command the simulation gets is the float's value.
      ASSERT_TRUE(client.SendTo(Local(0, CommandAt(k)), Loopback(field.blue_port())));
      ASSERT_TRUE(Receive(client)) << "no RobotControlResponse at frame " << k;
    }
    const ServeSummary& summary = server.Join();
    EXPECT_EQ(summary.counters.frames, frames);
    EXPECT_EQ(summary.counters.robot_controls, frames);
    EXPECT_EQ(summary.counters.refused, 0);
    // One work time per frame, one latency per command, each stamped by the kernel;
    // no lateness in lockstep.
    EXPECT_EQ(summary.timing.frame_work.count(), frames);
    EXPECT_EQ(summary.timing.command_latency.count(), frames);
    EXPECT_EQ(summary.timing.command_handling.count(), frames);
    EXPECT_EQ(summary.timing.unstamped, 0);
    EXPECT_EQ(summary.timing.start_lateness.count(), 0);
  }

  // The same scene and seed stepped in-process with the same commands, and with none.
  auto reference = [&](bool commanded) {
    Simulation sim = MakeSimulation(scene, "analytic");
    std::vector<std::vector<FrameRecord>> out;
    for (int k = 0; k < frames; ++k) {
      std::vector<FrameRecord> r = sim.BeginFrame();
      const Twist2 c = CommandAt(k);
      r[0].command = commanded ? Twist2{static_cast<float>(c.vx), static_cast<float>(c.vy), static_cast<float>(c.omega)}
                               : Twist2{};
      r[1].command = sim.SourceCommand(1);
      sim.EndFrame(&r);
      out.push_back(r);
    }
    return out;
  };
  const auto same = reference(true), still = reference(false);
  const SimulationResult& served = field.result();
  int first_moved = -1;
  for (int k = 0; k < frames; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    // Poses identical to the simulation's, to the bit.
    EXPECT_EQ(served.frames[0][ku].truth.x, same[ku][0].truth.x) << k;
    EXPECT_EQ(served.frames[0][ku].truth.theta, same[ku][0].truth.theta) << k;
    EXPECT_EQ(served.frames[1][ku].truth.y, same[ku][1].truth.y) << k;
    EXPECT_EQ(served.frames[0][ku].command.vx, same[ku][0].command.vx) << k;
    // Vision is the observer's pose in mm, as a float.
    ASSERT_EQ(seen[ku].robots_blue_size(), 1);
    ASSERT_EQ(seen[ku].robots_yellow_size(), 1);
    EXPECT_EQ(seen[ku].robots_yellow(0).robot_id(), 3u);
    EXPECT_EQ(seen[ku].robots_blue(0).x(), static_cast<float>(1000 * same[ku][0].seen.x)) << k;
    EXPECT_EQ(seen[ku].robots_blue(0).orientation(), static_cast<float>(same[ku][0].seen.theta)) << k;
    if (first_moved < 0 && seen[ku].robots_blue(0).x() != static_cast<float>(1000 * still[ku][0].seen.x))
      first_moved = k;
  }
  const OmniModel& m = scene.robots[0].model;
  const int delay = m.command_delay_frames + m.vision_delay_frames;
  EXPECT_EQ(delay, 4);
  EXPECT_EQ(first_moved, 10 + delay + 1);
}

// A backend per robot: blue 0 on ode (its own `backend:`), yellow 3 on the field's
// analytic. Lockstep serves it as it serves one backend: vision and poses to the bit
// those of the same mixed field stepped in-process with the same commands.
TEST(LiveField, LockstepServesAFieldOfSeveralBackends) {
  const std::vector<std::string> built = AvailableOmniBackends();
  if (std::find(built.begin(), built.end(), "ode") == built.end()) GTEST_SKIP() << "ode not built";
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  const Scene scene = LoadSceneFromString(
      "name: served\nbackend: analytic\nduration: 10\nseed: 7\nrobots:\n"
      "  - {name: b0, backend: ode, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
      "  - {name: y3, team: yellow, id: 3, model: " + model + ", start: {x: 1, y: 0.5, theta_deg: 90}, " + hold + "}\n",
      "served.yaml", ".");
  const int frames = 30;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  EXPECT_EQ(field.result().backend, "mixed: ode (b0), analytic (y3)");
  std::vector<SSL_DetectionFrame> seen;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      seen.push_back(*f);
      ASSERT_TRUE(client.SendTo(Local(0, CommandAt(k)), Loopback(field.blue_port())));
      ASSERT_TRUE(Receive(client)) << "no RobotControlResponse at frame " << k;
    }
    EXPECT_EQ(server.Join().counters.frames, frames);
  }
  Simulation sim = MakeSimulation(scene, "analytic");
  const SimulationResult& served = field.result();
  bool moved = false;
  for (int k = 0; k < frames; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    std::vector<FrameRecord> r = sim.BeginFrame();
    const Twist2 c = CommandAt(k);
    r[0].command = Twist2{static_cast<float>(c.vx), static_cast<float>(c.vy), static_cast<float>(c.omega)};
    r[1].command = sim.SourceCommand(1);
    sim.EndFrame(&r);
    EXPECT_EQ(served.frames[0][ku].truth.x, r[0].truth.x) << k;
    EXPECT_EQ(served.frames[0][ku].truth.theta, r[0].truth.theta) << k;
    EXPECT_EQ(served.frames[1][ku].truth.y, r[1].truth.y) << k;
    ASSERT_EQ(seen[ku].robots_blue_size(), 1);
    EXPECT_EQ(seen[ku].robots_blue(0).x(), static_cast<float>(1000 * r[0].seen.x)) << k;
    moved = moved || std::abs(r[0].truth.x) > 0.05;
  }
  EXPECT_TRUE(moved) << "the commanded ode robot should drive";
}

TEST(LiveField, RefusalsAreAnsweredAndCountedAndTheFieldRunsOn) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.max_datagram = 256;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServerThread server(&field);
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, Local(3, Twist2{1, 0, 0}), field.blue_port())),
            Codes1{"TWINSIM_OTHER_TEAM"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, Local(5, Twist2{1, 0, 0}), field.yellow_port())),
            Codes1{"TWINSIM_UNKNOWN_ROBOT"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, std::string(11, '\xff'), field.blue_port())),
            Codes1{"TWINSIM_MALFORMED"});
  const auto oversized = Ask<RobotControlResponse>(client, std::string(1000, '\x08'), field.blue_port());
  EXPECT_EQ(Codes(oversized), Codes1{"TWINSIM_OVERSIZED"});
  if (oversized && oversized->errors_size() == 1) {
    EXPECT_NE(oversized->errors(0).message().find("1000 bytes"), std::string::npos) << oversized->errors(0).message();
  }
  // Garbage on the control port is answered as well.
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, "\x0a\x05\x12", field.control_port())), Codes1{"TWINSIM_MALFORMED"});

  // A teleport through the control port shows in vision.
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportBlue0(-1.5f, 2.0f), field.control_port())), Codes1{});
  bool arrived = false;
  for (int i = 0; i < 60 && !arrived; ++i) {
    std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, 0);
    ASSERT_TRUE(f);
    arrived = f->robots_blue_size() == 1 && std::abs(f->robots_blue(0).x() + 1500) < 10 &&
              std::abs(f->robots_blue(0).y() - 2000) < 10;
  }
  EXPECT_TRUE(arrived);

  const ServeSummary& summary = server.Stop();
  EXPECT_EQ(summary.counters.refused, 2);
  EXPECT_EQ(summary.counters.malformed, 2);
  EXPECT_EQ(summary.counters.oversized, 1);
  EXPECT_EQ(summary.counters.simulator_commands, 1);
  EXPECT_GT(summary.counters.frames, 0);
  // Real time: a lateness for every frame begun (the last, stopped, one has no work).
  EXPECT_EQ(summary.timing.frame_work.count(), summary.counters.frames);
  EXPECT_GE(summary.timing.start_lateness.count(), summary.counters.frames);
  EXPECT_LE(summary.timing.start_lateness.count(), summary.counters.frames + 1);
  // The slowest frame and the latest start are the histograms' largest, named by frame.
  EXPECT_EQ(summary.timing.slowest.seconds, summary.timing.frame_work.max());
  EXPECT_GE(summary.timing.slowest.frame, 0);
  EXPECT_LT(summary.timing.slowest.frame, summary.counters.frames);
  EXPECT_GT(summary.timing.slowest.vision, 0);
  EXPECT_LE(summary.timing.slowest.vision, summary.timing.slowest.seconds);
  EXPECT_EQ(summary.timing.latest_start.seconds, summary.timing.start_lateness.max());
  EXPECT_GE(summary.timing.latest_start.frame, 0);
  EXPECT_LE(summary.timing.latest_start.frame, summary.counters.frames);
  EXPECT_GE(summary.timing.latest_start.woke_late, 0);
  // Where the CPU's stolen and interrupt time is known (the thread stayed on one CPU over
  // the span): no more than the span (in 10 ms ticks, one either way).
  const ServeTiming::Stall& late = summary.timing.latest_start;
  if (late.stolen >= 0) {
    EXPECT_GE(late.interrupts, 0);
    EXPECT_LE(late.stolen, late.seconds + 0.011);
    EXPECT_NE(late.Brief().find("CPU stolen"), std::string::npos);
  } else {
    EXPECT_EQ(late.Brief().find("CPU stolen"), std::string::npos);
  }
  EXPECT_NE(summary.Report().find("slowest frame " + summary.timing.slowest.Brief()), std::string::npos);
  // A latency for each RobotControl read, refused robots or not; none for bad datagrams.
  EXPECT_EQ(summary.timing.command_latency.count(), summary.counters.robot_controls);
}

TEST(LiveField, TournamentModeRefusesControlAndASecondAddressPerTeam) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), team("127.0.0.1", 0), intruder("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.tournament = true;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServerThread server(&field);

  EXPECT_EQ(Codes(Ask<SimulatorResponse>(team, TeleportBlue0(1.0f, 0.0f), field.control_port())),
            Codes1{"TWINSIM_TOURNAMENT"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(team, Local(0, Twist2{0.5, 0, 0}), field.blue_port())), Codes1{});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(intruder, Local(0, Twist2{-0.5, 0, 0}), field.blue_port())),
            Codes1{"TWINSIM_PORT_TAKEN"});
  // The yellow port is still open to the yellow team's own (first) address.
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(intruder, Local(3, Twist2{0.5, 0, 0}), field.yellow_port())), Codes1{});

  const ServeSummary& summary = server.Stop();
  EXPECT_EQ(summary.counters.refused, 2);
  EXPECT_EQ(summary.counters.robot_controls, 2);
  EXPECT_EQ(summary.counters.simulator_commands, 0);
}

TEST(LiveField, AFloodIsDroppedOverTheRateLimitWithoutStallingTheFrames) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), flooder("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.max_rate = 50;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServerThread server(&field);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 2000; ++i) {
    flooder.SendTo(Local(0, Twist2{0.1, 0, 0}), Loopback(field.blue_port()));
    if (i % 100 == 99) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const ServeSummary& summary = server.Stop();
  EXPECT_GT(summary.counters.rate_dropped, 0);
  EXPECT_LE(summary.counters.robot_controls, 50 + static_cast<long long>(50 * wall) + 1);
  // Frames kept coming (30 fps; half of it allowed for a loaded machine): no stall.
  EXPECT_GE(summary.counters.frames, static_cast<long long>(15 * wall) - 2);
}

// keep_frames: the sink gets every frame as it ends; result() keeps an evenly thinned
// history of the whole match (every 2^j-th frame), between keep_frames and twice as
// many, allocated once.
TEST(LiveField, TheSinkGetsEveryFrameAndTheHistoryIsThinnedEvenly) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions options = LockstepOptions(vision.port(), 37);
  options.keep_frames = 4;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  std::vector<double> sunk;  // t of each frame the sink got
  field.SetFrameSink([&](const std::vector<FrameRecord>& records, const BallRecord* ball) {
    EXPECT_EQ(records.size(), 2u);
    EXPECT_EQ(ball, nullptr);
    sunk.push_back(records[0].t);
  });
  const FrameRecord* first = field.result().frames[0].data();
  EXPECT_EQ(field.result().frames[0].capacity(), 8u);
  {
    ServerThread server(&field);
    for (int k = 0; k < 37; ++k) {
      ASSERT_TRUE(ReceiveFrame(vision, static_cast<std::uint32_t>(k))) << k;
      ASSERT_TRUE(Ask<RobotControlResponse>(client, Local(0, Twist2{0.2, 0, 0}), field.blue_port())) << k;
    }
    server.Join();
  }
  ASSERT_EQ(sunk.size(), 37u);
  const double dt = 1 / scene.frame_rate;
  for (std::size_t k = 0; k < sunk.size(); ++k) EXPECT_NEAR(sunk[k], k * dt, 1e-9);
  // Room for 8: full at frame 7 (kept 0, 2, 4, 6; then every 2nd), at frame 14 (0, 4, 8,
  // 12; every 4th) and at frame 28 (0, 8, 16, 24; every 8th); then 32.
  const std::vector<FrameRecord>& kept = field.result().frames[0];
  ASSERT_EQ(kept.size(), 5u);
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_NEAR(kept[i].t, 8.0 * i * dt, 1e-9) << i;
  EXPECT_EQ(field.result().frames[0].data(), first) << "the history was allocated again";
}

// A burst larger than the receive buffer: what the kernel drops before the loop reads
// it is counted (the count rides on the next datagram read), so every datagram sent is
// either handled or counted as dropped.
TEST(LiveField, DatagramsTheKernelDropsAreCounted) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), flooder("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.max_rate = 1e6;         // nothing dropped over the rate limit
  options.receive_buffer = 4096;  // the kernel's smallest: a few datagrams
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  EXPECT_LT(field.receive_buffer(), 65536);
  const int burst = 2000;
  const std::string command = Local(0, Twist2{0.1, 0, 0});
  for (int i = 0; i < burst; ++i) ASSERT_TRUE(flooder.SendTo(command, Loopback(field.blue_port())));
  ServerThread server(&field);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // One more, after the burst was read: it carries the kernel's count.
  ASSERT_TRUE(flooder.SendTo(command, Loopback(field.blue_port())));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const ServeSummary& summary = server.Stop();
  EXPECT_GT(summary.counters.kernel_dropped, burst / 2);
  EXPECT_EQ(summary.counters.robot_controls + summary.counters.kernel_dropped, burst + 1);
  EXPECT_NE(summary.Brief().find("dropped by the kernel"), std::string::npos) << summary.Brief();
}

// The default buffer holds a quarter second at the rate limit where the kernel allows.
TEST(LiveField, TheReceiveBufferIsSizedForTheRateLimit) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.max_rate = 400;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  EXPECT_EQ(field.receive_buffer_asked(), static_cast<int>(400 * LiveField::kBufferedSeconds * LiveField::kDatagramCost));
  // Granted as asked (300 kB, under twice Linux's default net.core.rmem_max of 208 kB).
  EXPECT_GE(field.receive_buffer(), field.receive_buffer_asked());
  EXPECT_LT(field.receive_buffer(), field.receive_buffer_asked() + 4096);
}

// Vision to the broadcast address, which a socket may not send to without SO_BROADCAST:
// every refused send is counted, with the system's reason.
TEST(LiveField, RefusedSendsAreCountedWithTheReason) {
  const Scene scene = TwoTeamScene();
  ServeOptions options = LoopbackOptions(10020);
  options.vision_address = "255.255.255.255";
  options.max_frames = 4;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  const ServeSummary summary = field.Run([] { return false; });
  EXPECT_EQ(summary.counters.frames, 4);
  EXPECT_EQ(summary.counters.failed_sends, 4);
  EXPECT_EQ(summary.last_send_error, std::strerror(EACCES));
  EXPECT_NE(summary.Brief().find("4 sends failed (" + std::string(std::strerror(EACCES)) + ")"), std::string::npos)
      << summary.Brief();
}

// Real time at half speed: t_capture is the wall clock when the captured frame began
// (the time the packet of that frame was sent, less its work), not the start plus
// simulated time, which falls behind by a frame period each frame at half speed.
TEST(LiveField, RealTimeCaptureTimesFollowTheWallClockWhenTheSpeedChanges) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.max_frames = 24;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  const int delay = field.simulation().robot_model(0).vision_delay_frames;
  ASSERT_GT(delay, 0);
  std::map<std::uint32_t, std::pair<double, double>> stamps;  // frame: t_capture, t_sent
  {
    ServerThread server(&field);
    SimulatorCommand slow;
    slow.mutable_control()->set_simulation_speed(0.5f);
    ASSERT_TRUE(Ask<SimulatorResponse>(client, slow.SerializeAsString(), field.control_port()));
    for (std::uint32_t k = 0; k < 24; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, k);
      ASSERT_TRUE(f) << "no vision for frame " << k;
      const double now =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      EXPECT_NEAR(f->t_sent(), now, 0.05) << k;
      stamps[f->frame_number()] = {f->t_capture(), f->t_sent()};
      k = f->frame_number();
    }
    server.Join();
  }
  int compared = 0;
  for (const auto& [k, t] : stamps) {
    const auto earlier = stamps.find(k - static_cast<std::uint32_t>(delay));
    if (k < static_cast<std::uint32_t>(delay) || earlier == stamps.end()) continue;
    // The captured frame began before its packet went out, by its capture's work.
    EXPECT_NEAR(t.first, earlier->second.second, 0.005) << "frame " << k;
    EXPECT_LE(t.first, earlier->second.second) << "frame " << k;
    ++compared;
  }
  EXPECT_GE(compared, 15);
}

TEST(LiveField, LockstepRecoversWhenAnAnswerIsLostOverTheRateLimit) {
  // A bucket of 2 datagrams a second: from the third frame on, most answers are dropped
  // unanswered. The frame's vision goes out again every 0.25 s and the client answers
  // each copy, so every frame is stepped (one is let through as the bucket refills)
  // and the field never stalls.
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), team("127.0.0.1", 0);
  ServeOptions options = LockstepOptions(vision.port(), 5);
  options.max_rate = 2;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServerThread server(&field);
  int answered = 0;
  while (answered < 40) {
    if (!Receive(vision, 2)) break;  // the field ended (no vision for 2 s)
    team.SendTo(Local(0, Twist2{0.2, 0, 0}), Loopback(field.blue_port()));
    ++answered;
  }
  const ServeSummary& summary = server.Stop();  // a stalled field fails here, not hangs
  EXPECT_EQ(summary.counters.frames, 5);
  EXPECT_GT(summary.counters.rate_dropped, 0);
  EXPECT_GT(summary.counters.vision_packets, 5);  // the frames' vision sent again
}

// Blue 0 at the origin facing +x with the ball touching its flat front; yellow 3 aside.
Scene BallScene() {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  const double front = testing::Omni4().FrontDistance() + BallModel{}.radius;
  return LoadSceneFromString("name: served_ball\nbackend: analytic\nframe_rate: 60\nduration: 10\nseed: 7\nrobots:\n"
                             "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
                             "  - {name: y3, team: yellow, id: 3, model: " + model +
                                 ", start: {x: 1, y: 1.5, theta_deg: 90}, " + hold + "}\n"
                             "ball: {drag: 0, start: {x: " + std::to_string(front) + ", y: 0}}\n",
                             "served_ball.yaml", ".");
}

// Blue robot 0 standing still, kicking at `kick` m/s (0: none), dribbling at `dribbler` rpm.
std::string KickBlue0(float kick, float angle_deg, float dribbler) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(0);
  c->mutable_move_command()->mutable_local_velocity()->set_forward(0);
  c->mutable_move_command()->mutable_local_velocity()->set_left(0);
  c->mutable_move_command()->mutable_local_velocity()->set_angular(0);
  if (kick != 0) c->set_kick_speed(kick);
  if (angle_deg != 0) c->set_kick_angle(angle_deg);
  if (dribbler != 0) c->set_dribbler_speed(dribbler);
  return control.SerializeAsString();
}

std::string BallTeleportCommand(float x, float y, float vx, bool by_force = false) {
  SimulatorCommand command;
  ::TeleportBall* t = command.mutable_control()->mutable_teleport_ball();
  t->set_x(x);
  t->set_y(y);
  t->set_vx(vx);
  t->set_by_force(by_force);
  return command.SerializeAsString();
}

TEST(LiveField, TheBallIsSeenKickedDribbledTeleportedAndLogged) {
  const Scene scene = BallScene();
  const int frames = 40, kick_frame = 5;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  const ServeOptions options = LockstepOptions(vision.port(), frames);
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  std::vector<SSL_DetectionFrame> seen;
  std::vector<bool> contact;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      seen.push_back(*f);
      if (k == 30) {
        // The referee's hand: the ball to (-1, 1), at rest.
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(-1, 1, 0), field.control_port())), Codes1{});
      }
      const auto r = Ask<RobotControlResponse>(client, KickBlue0(k == kick_frame ? 3.0f : 0.0f, 0, k < kick_frame ? 500.0f : 0.0f),
                                               field.blue_port());
      ASSERT_TRUE(r) << "no RobotControlResponse at frame " << k;
      EXPECT_EQ(Codes(r), Codes1{}) << k;
      ASSERT_EQ(r->feedback_size(), 1);
      contact.push_back(r->feedback(0).dribbler_ball_contact());
    }
    server.Join();
  }
  // The ball in every frame, in mm: at the front until the kick acts (sent at frame 5,
  // acting from frame 5 + 2, first seen moved at 5 + 4 + 1).
  const double front_mm = 1000 * (testing::Omni4().FrontDistance() + BallModel{}.radius);
  int first_moved = -1;
  for (int k = 0; k < 30; ++k) {
    ASSERT_EQ(seen[static_cast<std::size_t>(k)].balls_size(), 1) << k;
    const SSL_DetectionBall& b = seen[static_cast<std::size_t>(k)].balls(0);
    EXPECT_NEAR(b.z(), 21.5, 0.5) << k;
    if (first_moved < 0 && std::abs(b.x() - front_mm) > 1) first_moved = k;
  }
  EXPECT_EQ(first_moved, kick_frame + 4 + 1);
  // Seen between frames 19 and 20: the truth of frames 17 and 18, 10.5 frames after
  // the kick, still sliding (mu g = 3.4 m/s^2).
  const double speed = (seen[20].balls(0).x() - seen[19].balls(0).x()) * 60 / 1000;  // m/s
  EXPECT_NEAR(speed, 3 - 0.35 * kGravity * 10.5 / 60.0, 0.05);
  // The robot felt the ball on its dribbler before the kick (the answer to frame k tells
  // the state after frame k - 1), not after.
  EXPECT_TRUE(contact[1]);
  EXPECT_TRUE(contact[static_cast<std::size_t>(kick_frame)]);
  EXPECT_FALSE(contact[20]);
  // The teleport (during frame 30) shows after the camera's delay, from frame 33 on.
  EXPECT_GT(std::abs(seen[32].balls(0).x() + 1000), 100);
  for (int k = 33; k < frames; ++k) {
    EXPECT_NEAR(seen[static_cast<std::size_t>(k)].balls(0).x(), -1000, 1) << k;
    EXPECT_NEAR(seen[static_cast<std::size_t>(k)].balls(0).y(), 1000, 1) << k;
  }
  // Ctrl-C's log has the ball's path.
  ASSERT_EQ(field.result().ball.size(), static_cast<std::size_t>(frames));
  EXPECT_NEAR(field.result().ball[20].truth.velocity.x(), 3 - 0.35 * kGravity * 13 / 60.0, 0.1);
}

TEST(LiveField, BadKicksAndBallTeleportsAreRefused) {
  const Scene scene = BallScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LoopbackOptions(vision.port()));
  ServerThread server(&field);
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, KickBlue0(-1, 0, 0), field.blue_port())), Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, KickBlue0(3, 95, 0), field.blue_port())), Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, KickBlue0(0, 0, -10), field.blue_port())), Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, KickBlue0(std::nanf(""), 0, 0), field.blue_port())),
            Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(9, 0, 0), field.control_port())), Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(0, 0, 50), field.control_port())), Codes1{"TWINSIM_BAD_VALUE"});
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(9, 0, 0, true), field.control_port())),
            Codes1{"TWINSIM_BAD_VALUE"});
  const ServeSummary& summary = server.Stop();
  EXPECT_EQ(summary.counters.refused, 7);
}

TEST(LiveField, WithoutABallKicksAndBallTeleportsAnswerNoBall) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LoopbackOptions(vision.port()));
  ServerThread server(&field);
  EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, KickBlue0(3, 0, 0), field.blue_port())), Codes1{"TWINSIM_NO_BALL"});
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(0, 0, 0), field.control_port())), Codes1{"TWINSIM_NO_BALL"});
}

TEST(LiveField, OptionsAndScenesAreChecked) {
  const Scene scene = TwoTeamScene();
  ServeOptions options = LoopbackOptions(10020);
  std::string why;
  options.vision_ttl = 4;  // multicast options for a unicast address
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("multicast"), std::string::npos) << why;
  options.vision_address = "224.5.23.2";
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.vision_ttl = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--vision-ttl 0"), std::string::npos) << why;
  options = LoopbackOptions(10020);
  options.realtime_priority = 100;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("0..99"), std::string::npos) << why;
  options.realtime_priority = 10;
  options.lockstep = true;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("real time"), std::string::npos) << why;
  options = LoopbackOptions(10020);
  options.listen = "localhost:1";
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("not an IPv4 address"), std::string::npos) << why;
  options = LoopbackOptions(10020);
  options.teams = {"red"};
  options.lockstep = true;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("unknown team 'red'"), std::string::npos) << why;
  // A port in use is named.
  UdpSocket taken("127.0.0.1", 0);
  options = LoopbackOptions(10020);
  options.blue_port = taken.port();
  try {
    LiveField field(scene, MakeSimulation(scene, "analytic"), options);
    FAIL() << "expected the port in use to be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(taken.port())),
              std::string::npos)
        << e.what();
  }
}

// Multicast vision is only set up here, never sent (tests stay off multicast groups):
// the socket gets the ttl, the loop to this host's members and the interface asked for.
TEST(LiveField, AMulticastVisionSocketGetsItsTtlLoopAndInterface) {
  UdpSocket out;
  out.SetMulticastSender(3, true, "127.0.0.1");
  unsigned char ttl = 0, loop = 0;
  in_addr interface{};
  socklen_t n = sizeof ttl;
  ASSERT_EQ(getsockopt(out.fd(), IPPROTO_IP, IP_MULTICAST_TTL, &ttl, &n), 0);
  n = sizeof loop;
  ASSERT_EQ(getsockopt(out.fd(), IPPROTO_IP, IP_MULTICAST_LOOP, &loop, &n), 0);
  n = sizeof interface;
  ASSERT_EQ(getsockopt(out.fd(), IPPROTO_IP, IP_MULTICAST_IF, &interface, &n), 0);
  EXPECT_EQ(ttl, 3);
  EXPECT_EQ(loop, 1);
  EXPECT_EQ(ntohl(interface.s_addr), ParseIpv4("127.0.0.1"));
  EXPECT_THROW(out.SetMulticastSender(0, true, ""), InputError);
  // An address that is not this host's is refused by the system, and named.
  try {
    out.SetMulticastSender(1, true, "192.0.2.77");
    FAIL() << "expected a foreign interface address to be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("192.0.2.77"), std::string::npos) << e.what();
  }
  // A served field takes the league's group (and sends nothing until it runs).
  const Scene scene = TwoTeamScene();
  ServeOptions options = LoopbackOptions(10020);
  options.vision_address = "224.5.23.2";
  EXPECT_NO_THROW(LiveField(scene, MakeSimulation(scene, "analytic"), options));
}

// --realtime-priority: the serving thread runs at SCHED_FIFO while the field runs and
// gets its old policy back after; where the system refuses (no CAP_SYS_NICE), the
// refusal says what is needed.
TEST(LiveField, RealTimePriorityHoldsWhileServingAndIsGivenBack) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.realtime_priority = 10;
  options.cpu = 0;
  options.max_frames = 3;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  int policy_before = -1, policy_during = -1, policy_after = -1, cpus_during = 0;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &policy_before, &param);
  try {
    field.Run([] { return false; },
              [&](const ServeSummary&) {
                pthread_getschedparam(pthread_self(), &policy_during, &param);
                cpu_set_t set;
                pthread_getaffinity_np(pthread_self(), sizeof set, &set);
                cpus_during = CPU_COUNT(&set);
              });
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("CAP_SYS_NICE"), std::string::npos) << e.what();
    GTEST_SKIP() << "this system refuses SCHED_FIFO: " << e.what();
  }
  pthread_getschedparam(pthread_self(), &policy_after, &param);
  EXPECT_EQ(policy_during, SCHED_FIFO);
  EXPECT_EQ(cpus_during, 1);
  EXPECT_EQ(policy_after, policy_before);
}

// Blue 0, yellow 3, and blue 1 off the field at the start (the scene's `present: false`).
Scene SquadScene(const std::string& ball = "") {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  return LoadSceneFromString("name: squad\nbackend: analytic\nframe_rate: 60\nduration: 10\nseed: 7\nrobots:\n"
                             "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
                             "  - {name: y3, team: yellow, id: 3, model: " + model +
                                 ", start: {x: 1, y: 1.5, theta_deg: 90}, " + hold + "}\n"
                             "  - {name: b1, id: 1, present: false, model: " + model +
                                 ", start: {x: -2, y: 1}, " + hold + "}\n" + ball,
                             "squad.yaml", ".");
}

// A SimulatorCommand with one teleport of `team`'s robot `id`; `present` set unless null.
std::string TeleportCommand(Team team, unsigned id, std::optional<bool> present, std::optional<Pose2> pose,
                            bool by_force = false) {
  SimulatorCommand command;
  TeleportRobot* t = command.mutable_control()->add_teleport_robot();
  t->mutable_id()->set_id(id);
  t->mutable_id()->set_team(team);
  if (present) t->set_present(*present);
  if (pose) {
    t->set_x(static_cast<float>(pose->x));
    t->set_y(static_cast<float>(pose->y));
    t->set_orientation(static_cast<float>(pose->theta));
  }
  if (by_force) t->set_by_force(true);
  return command.SerializeAsString();
}

// Whether the detection frame shows `team`'s robot `id`, and where (mm).
std::optional<Eigen::Vector2d> Sighted(const SSL_DetectionFrame& f, Team team, unsigned id) {
  const auto& robots = team == BLUE ? f.robots_blue() : f.robots_yellow();
  for (const SSL_DetectionRobot& r : robots)
    if (r.robot_id() == id) return Eigen::Vector2d(r.x(), r.y());
  return std::nullopt;
}

TEST(LiveField, RobotsAreAddedAndRemovedAndOffTheFieldTheyAreNeitherSeenNorCommanded) {
  const Scene scene = SquadScene();
  const int frames = 30;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  std::vector<SSL_DetectionFrame> seen;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      seen.push_back(*f);
      if (k == 2) {
        // Blue 1 is off the field: not teleported without present: true (nor commanded:
        // the team's message below).
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 1, std::nullopt, Pose2{1, 1, 0}),
                                               field.control_port())),
                  Codes1{"TWINSIM_NOT_PRESENT"});
        // A robot the scene does not have stays unknown: the scene is the squad.
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 7, true, Pose2{1, 1, 0}),
                                               field.control_port())),
                  Codes1{"TWINSIM_UNKNOWN_ROBOT"});
      }
      if (k == 5) {
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 1, true, Pose2{2, -1, 1}),
                                               field.control_port())),
                  Codes1{});
      }
      if (k == 15) {
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(YELLOW, 3, false, std::nullopt),
                                               field.control_port())),
                  Codes1{});
      }
      // Yellow 3 is refused from then on (the yellow team, once it has sent, is waited
      // for in lockstep: it answers every frame).
      if (k >= 15) {
        EXPECT_EQ(Codes(Ask<RobotControlResponse>(client, Local(3, Twist2{1, 0, 0}), field.yellow_port())),
                  Codes1{"TWINSIM_NOT_PRESENT"})
            << k;
      }
      // Blue 1, once added, takes commands like any robot (standing still here).
      RobotControl control;
      for (unsigned id : {0u, 1u}) {
        RobotCommand* c = control.add_robot_commands();
        c->set_id(id);
        c->mutable_move_command()->mutable_local_velocity()->set_forward(0);
        c->mutable_move_command()->mutable_local_velocity()->set_left(0);
        c->mutable_move_command()->mutable_local_velocity()->set_angular(0);
      }
      const auto r = Ask<RobotControlResponse>(client, control.SerializeAsString(), field.blue_port());
      ASSERT_TRUE(r) << k;
      EXPECT_EQ(Codes(r), k < 5 ? Codes1{"TWINSIM_NOT_PRESENT"} : Codes1{}) << k;
    }
    const ServeSummary& summary = server.Join();
    // Frames 0..4 refuse blue 1's command, frame 2 two requests, frames 15..29 yellow 3's.
    EXPECT_EQ(summary.counters.refused, 5 + 2 + 15);
  }
  // Vision shows what the camera captured two frames earlier: blue 1 from frame 8 (added
  // during frame 5, captured from 6) where it was put; yellow 3 until frame 17 (removed
  // during frame 15, last captured in 15).
  for (int k = 0; k < frames; ++k) {
    const SSL_DetectionFrame& f = seen[static_cast<std::size_t>(k)];
    const std::optional<Eigen::Vector2d> b1 = Sighted(f, BLUE, 1), y3 = Sighted(f, YELLOW, 3);
    EXPECT_EQ(b1.has_value(), k >= 8) << k;
    EXPECT_EQ(y3.has_value(), k <= 17) << k;
    EXPECT_TRUE(Sighted(f, BLUE, 0).has_value()) << k;
    if (b1) {
      EXPECT_NEAR(b1->x(), 2000, 5) << k;
      EXPECT_NEAR(b1->y(), -1000, 5) << k;
    }
  }
  // The logs: blue 1 and yellow 3 are on the field in the frames they were.
  const SimulationResult& result = field.result();
  for (int k = 0; k < frames; ++k) {
    EXPECT_EQ(result.frames[2][static_cast<std::size_t>(k)].present, k >= 6) << k;
    EXPECT_EQ(result.frames[1][static_cast<std::size_t>(k)].present, k <= 15) << k;
  }
  EXPECT_FALSE(field.simulation().present(1));
  EXPECT_TRUE(field.simulation().present(2));
}

TEST(LiveField, MovesByForceArriveWithoutAJump) {
  const Scene scene = SquadScene("ball: {start: {x: 1, y: -1}}\n");
  const int frames = 200;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  const Pose2 target{1.0, 0.5, 1.0};
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      ASSERT_TRUE(ReceiveFrame(vision, static_cast<std::uint32_t>(k))) << "no vision for frame " << k;
      if (k == 3) {
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 0, std::nullopt, target, true),
                                               field.control_port())),
                  Codes1{});
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, BallTeleportCommand(-1.0f, 1.5f, 0, true), field.control_port())),
                  Codes1{});
        // Off the field a robot cannot be moved by force.
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 1, true, target, true),
                                               field.control_port())),
                  Codes1{"TWINSIM_NOT_PRESENT"});
      }
      // The team keeps sending "stand still": the move by force overrides it.
      ASSERT_TRUE(Ask<RobotControlResponse>(client, Local(0, Twist2{}), field.blue_port())) << k;
    }
    server.Join();
  }
  const SimulationResult& result = field.result();
  const double dt = 1.0 / 60;
  for (int k = 1; k < frames; ++k) {
    const Pose2& a = result.frames[0][static_cast<std::size_t>(k - 1)].truth;
    const Pose2& b = result.frames[0][static_cast<std::size_t>(k)].truth;
    EXPECT_LE(std::hypot(b.x - a.x, b.y - a.y), 1.1 * Simulation::kPullSpeed * dt) << k;
    const Eigen::Vector3d& p = result.ball[static_cast<std::size_t>(k - 1)].truth.position;
    const Eigen::Vector3d& q = result.ball[static_cast<std::size_t>(k)].truth.position;
    EXPECT_LE((q - p).norm(), 1.1 * BallField::kPullSpeed * dt) << k;
  }
  // It got there (within the pull's tolerance), and let go it stays near (the last
  // few cm/s of the approach).
  double nearest = 1;
  for (const FrameRecord& f : result.frames[0])
    nearest = std::min(nearest, std::hypot(f.truth.x - target.x, f.truth.y - target.y));
  EXPECT_LT(nearest, Simulation::kPullTolerance);
  const Pose2& end = result.frames[0].back().truth;
  EXPECT_LT(std::hypot(end.x - target.x, end.y - target.y), 0.02);
  EXPECT_LT(std::abs(WrapAngle(end.theta - target.theta)), 2 * Simulation::kPullAngleTolerance);
  const Eigen::Vector3d& ball = result.ball.back().truth.position;
  EXPECT_LT(std::hypot(ball.x() + 1, ball.y() - 1.5), 0.02);
  // Both were let go.
  EXPECT_FALSE(field.simulation().pull(0).has_value());
  EXPECT_FALSE(field.simulation().ball()->pull().has_value());
}

TEST(LiveField, TheBallTeleportedSafelyMovesRobotsOutOfItsWay) {
  const Scene scene = SquadScene("ball: {start: {x: 1, y: -1}}\n");
  const int frames = 6;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  // Onto blue 0 (at the origin, facing +x): just before its flat front, 5 mm off its axis.
  const float bx = static_cast<float>(testing::Omni4().FrontDistance() + 0.01), by = 0.005f;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      ASSERT_TRUE(ReceiveFrame(vision, static_cast<std::uint32_t>(k))) << "no vision for frame " << k;
      if (k == 2) {
        SimulatorCommand command;
        ::TeleportBall* t = command.mutable_control()->mutable_teleport_ball();
        t->set_x(bx);
        t->set_y(by);
        t->set_teleport_safely(true);
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, command.SerializeAsString(), field.control_port())), Codes1{});
      }
      ASSERT_TRUE(Ask<RobotControlResponse>(client, Local(0, Twist2{}), field.blue_port())) << k;
    }
    server.Join();
  }
  const SimulationResult& result = field.result();
  // Frame 3 starts after the teleport: blue 0 backed off to leave exactly the margin
  // between the ball and its front (the shortest way: straight back, with the heading
  // kept); yellow 3, far away, did not move.
  const Pose2& b0 = result.frames[0][3].truth;
  const Eigen::Vector3d& placed = result.ball[3].truth.position;
  EXPECT_NEAR(placed.x(), bx, 1e-6);
  const double gap = bx - b0.x - testing::Omni4().FrontDistance() - BallModel{}.radius;
  EXPECT_NEAR(gap, LiveField::kBallMargin, 1e-4);
  EXPECT_NEAR(b0.y, 0, 1e-4);
  EXPECT_NEAR(b0.theta, 0, 1e-6);
  EXPECT_EQ(result.frames[1][3].truth.x, result.frames[1][2].truth.x);
  EXPECT_EQ(result.frames[1][3].truth.y, result.frames[1][2].truth.y);
}

TEST(LiveField, ConfigurationMovesVisionAndSetsTheCameraNoiseAndRefusesTheRest) {
  const Scene scene = SquadScene();
  const int frames = 12;
  UdpSocket vision("127.0.0.1", 0), vision2("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  std::vector<SSL_DetectionFrame> seen;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      // From frame 4 on vision comes to the new port.
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(k < 4 ? vision : vision2, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      seen.push_back(*f);
      if (k == 3) {
        SimulatorCommand command;
        SimulatorConfig* config = command.mutable_config();
        config->set_vision_port(static_cast<unsigned>(vision2.port()));
        RealismConfigErForce realism;
        realism.set_stddev_robot_p(0);
        realism.set_stddev_robot_phi(0);
        realism.set_robot_command_loss(0.5f);
        config->mutable_realism_config()->add_custom()->PackFrom(realism);
        RobotSpecs* specs = config->add_robot_specs();
        specs->mutable_id()->set_id(0);
        specs->mutable_id()->set_team(BLUE);
        specs->set_radius(0.1f);
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, command.SerializeAsString(), field.control_port())),
                  (Codes1{"TWINSIM_UNSUPPORTED", "TWINSIM_UNSUPPORTED"}));
      }
      ASSERT_TRUE(Ask<RobotControlResponse>(client, Local(0, Twist2{0.5, 0, 0.5}), field.blue_port())) << k;
    }
    server.Join();
  }
  EXPECT_EQ(field.vision_to().port, vision2.port());
  // Noise 1 mm before; none in what was captured from frame 4 on (seen from frame 6).
  const SimulationResult& result = field.result();
  int exact_before = 0;
  for (int k = 2; k < frames; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    const Pose2& captured = result.frames[0][ku - 2].truth;
    const SSL_DetectionRobot& r = seen[ku].robots_blue(0);
    const bool exact = r.x() == static_cast<float>(1000 * captured.x) && r.y() == static_cast<float>(1000 * captured.y) &&
                       r.orientation() == static_cast<float>(captured.theta);
    if (k >= 6) {
      EXPECT_TRUE(exact) << k;
    } else if (exact) {
      ++exact_before;
    }
  }
  EXPECT_EQ(exact_before, 0);
}

TEST(LiveField, TournamentModeRefusesConfiguration) {
  const Scene scene = TwoTeamScene();
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions options = LoopbackOptions(vision.port());
  options.tournament = true;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServerThread server(&field);
  SimulatorCommand command;
  command.mutable_config()->set_vision_port(static_cast<unsigned>(client.port()));
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, command.SerializeAsString(), field.control_port())),
            Codes1{"TWINSIM_TOURNAMENT"});
  EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, TeleportCommand(BLUE, 0, false, std::nullopt), field.control_port())),
            Codes1{"TWINSIM_TOURNAMENT"});
  server.Stop();
  EXPECT_EQ(field.vision_to().port, vision.port());
  EXPECT_TRUE(field.simulation().present(0));
}

// The ball's camera over the protocol (SimulatorConfig's ER-Force realism): every
// detection missed, then seen with 5 mm of noise; the ball itself never moves.
TEST(LiveField, TheBallsCameraNoiseAndMissedDetectionsAreSetOverTheProtocol) {
  const Scene scene = BallScene();
  const int frames = 70;
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  LiveField field(scene, MakeSimulation(scene, "analytic"), LockstepOptions(vision.port(), frames));
  auto realism = [](float noise, float missing) {
    SimulatorCommand command;
    RealismConfigErForce r;
    r.set_stddev_ball_p(noise);
    r.set_missing_ball_detections(missing);
    command.mutable_config()->mutable_realism_config()->add_custom()->PackFrom(r);
    return command.SerializeAsString();
  };
  std::vector<SSL_DetectionFrame> seen;
  {
    ServerThread server(&field);
    for (int k = 0; k < frames; ++k) {
      std::optional<SSL_DetectionFrame> f = ReceiveFrame(vision, static_cast<std::uint32_t>(k));
      ASSERT_TRUE(f) << "no vision for frame " << k;
      seen.push_back(*f);
      if (k == 5) {
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, realism(0, 1), field.control_port())), Codes1{});
      }
      if (k == 20) {
        EXPECT_EQ(Codes(Ask<SimulatorResponse>(client, realism(0.005f, 0), field.control_port())), Codes1{});
      }
      ASSERT_TRUE(Ask<RobotControlResponse>(client, Local(0, Twist2{}), field.blue_port())) << k;
    }
    server.Join();
  }
  // Captured from frame 6 on without the ball (seen after the camera's delay of 2), from
  // frame 21 on with noise.
  const int delay = testing::Omni4().vision_delay_frames;
  for (int k = 0; k < 6 + delay; ++k) EXPECT_EQ(seen[static_cast<std::size_t>(k)].balls_size(), 1) << k;
  for (int k = 6 + delay; k < 21 + delay; ++k) EXPECT_EQ(seen[static_cast<std::size_t>(k)].balls_size(), 0) << k;
  const double truth_mm = 1000 * field.result().ball.back().truth.position.x();
  double sum = 0;
  int n = 0;
  for (int k = 21 + delay; k < frames; ++k) {
    ASSERT_EQ(seen[static_cast<std::size_t>(k)].balls_size(), 1) << k;
    const double e = seen[static_cast<std::size_t>(k)].balls(0).x() - truth_mm;
    sum += e * e;
    ++n;
  }
  // 47 draws: the spread within 30 % of 5 mm.
  EXPECT_NEAR(std::sqrt(sum / n), 5.0, 1.5);
}

}  // namespace
}  // namespace twinsim
