#include "serve/live_field.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <sstream>

#include "core/error.h"
#include "grSim_Robotstatus.pb.h"
#include "serve/ball_clearance.h"
#include "serve/cpu_time.h"
#include "serve/grsim_packet.h"
#include "serve/vision_packets.h"

namespace twinsim {
namespace {

// Raises the calling thread to SCHED_FIFO at `priority` (0: leaves it) and pins it to
// `cpu` (-1: leaves it) while it lives; puts the thread's policy and CPUs back after.
class RealtimeScope {
 public:
  RealtimeScope(int priority, int cpu) {
    const pthread_t self = pthread_self();
    if (priority > 0) {
      pthread_getschedparam(self, &old_policy_, &old_param_);
      sched_param p{};
      p.sched_priority = priority;
      if (const int err = pthread_setschedparam(self, SCHED_FIFO, &p); err != 0) {
        throw InputError("--realtime-priority " + std::to_string(priority) + ": the system refused SCHED_FIFO (" +
                         std::strerror(err) + "); it needs root, CAP_SYS_NICE or an rtprio limit (ulimit -r)");
      }
      raised_ = true;
    }
    if (cpu >= 0) {
      pthread_getaffinity_np(self, sizeof old_cpus_, &old_cpus_);
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(cpu, &set);
      if (const int err = pthread_setaffinity_np(self, sizeof set, &set); err != 0) {
        Restore();
        throw InputError("--cpu " + std::to_string(cpu) + ": the system refused to pin the thread there (" +
                         std::strerror(err) + ")");
      }
      pinned_ = true;
    }
  }
  ~RealtimeScope() { Restore(); }
  RealtimeScope(const RealtimeScope&) = delete;
  RealtimeScope& operator=(const RealtimeScope&) = delete;

 private:
  void Restore() {
    if (raised_) pthread_setschedparam(pthread_self(), old_policy_, &old_param_);
    if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof old_cpus_, &old_cpus_);
    raised_ = pinned_ = false;
  }

  int old_policy_ = SCHED_OTHER;
  sched_param old_param_{};
  cpu_set_t old_cpus_{};
  bool raised_ = false, pinned_ = false;
};

using Clock = std::chrono::steady_clock;

// Datagrams read from one port before the loop looks at the clock again: a flood
// cannot hold a frame.
constexpr int kMaxDatagramsPerDrain = 256;
// Lockstep with a team still to come or an answer still missing: the current frame's
// vision again this often.
constexpr double kResendPeriod = 0.25;  // s


double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// What the kernel has done to the calling thread so far, and to its CPU.
struct Usage {
  rusage thread{};
  CpuTicks cpu;
};

Usage UsageNow(const CpuTime& cpu) {
  Usage u;
  getrusage(RUSAGE_THREAD, &u.thread);
  u.cpu = cpu.Now();
  return u;
}

// Frame `frame`'s stall of `seconds` (`vision` s of it the vision), with what the kernel
// did to the thread and `cpu` over the spans given, each from its [0] to its [1].
ServeTiming::Stall StallOf(long long frame, double seconds, double vision, const CpuTime& cpu,
                           std::initializer_list<std::array<Usage, 2>> spans) {
  ServeTiming::Stall s;
  s.frame = frame;
  s.seconds = seconds;
  s.vision = vision;
  // The CPU's accounting where every span stayed on one CPU that could be read.
  bool cpu_known = true;
  for (const auto& [from, to] : spans) cpu_known = cpu_known && from.cpu.cpu >= 0 && from.cpu.cpu == to.cpu.cpu;
  if (cpu_known) s.stolen = s.interrupts = 0;
  for (const auto& [from, to] : spans) {
    s.minor_faults += to.thread.ru_minflt - from.thread.ru_minflt;
    s.major_faults += to.thread.ru_majflt - from.thread.ru_majflt;
    s.voluntary += to.thread.ru_nvcsw - from.thread.ru_nvcsw;
    s.involuntary += to.thread.ru_nivcsw - from.thread.ru_nivcsw;
    if (!cpu_known) continue;
    s.stolen += cpu.Seconds(to.cpu.steal - from.cpu.steal);
    s.interrupts += cpu.Seconds(to.cpu.interrupts - from.cpu.interrupts);
  }
  return s;
}

double UnixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// ns since the Unix epoch, the base of a datagram's arrival stamp.
long long UnixNanos() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

bool ServeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    *why = message;
    return false;
  };
  try {
    ParseIpv4(listen);
  } catch (const InputError& e) {
    return fail(std::string("--listen: ") + e.what());
  }
  std::uint32_t vision = 0;
  try {
    vision = ParseIpv4(vision_address);
  } catch (const InputError& e) {
    return fail(std::string("--vision-address: ") + e.what());
  }
  if (!IsMulticast(vision) && (vision_ttl != 1 || !vision_interface.empty()))
    return fail("--vision-ttl and --vision-interface apply to a multicast --vision-address (224.0.0.0/4) only");
  if (vision_ttl < 1 || vision_ttl > 255) return fail("--vision-ttl " + std::to_string(vision_ttl) + " is not in 1..255");
  if (!vision_interface.empty()) {
    try {
      ParseIpv4(vision_interface);
    } catch (const InputError& e) {
      return fail(std::string("--vision-interface: ") + e.what());
    }
  }
  if (realtime_priority < 0 || realtime_priority > 99)
    return fail("--realtime-priority " + std::to_string(realtime_priority) + " is not in 0..99");
  if (cpu < -1 || cpu >= CPU_SETSIZE) return fail("--cpu " + std::to_string(cpu) + " is not a CPU number");
  if ((realtime_priority > 0 || cpu >= 0) && lockstep)
    return fail("--realtime-priority and --cpu apply to real time, not --lockstep");
  for (const auto& [name, port] : {std::pair<const char*, int>{"--control-port", control_port},
                                   {"--blue-port", blue_port},
                                   {"--yellow-port", yellow_port}})
    if (port < 0 || port > 65535) return fail(std::string(name) + " " + std::to_string(port) + " is not in 0..65535");
  if (grsim_port < -1 || grsim_port > 65535) return fail("--grsim-port " + std::to_string(grsim_port) + " is not in 0..65535");
  if (grsim_port > 0 && (grsim_port == control_port || grsim_port == blue_port || grsim_port == yellow_port))
    return fail("--grsim-port must differ from the control, blue and yellow ports");
  for (const auto& [name, port] : {std::pair<const char*, int>{"--grsim-blue-status-port", grsim_blue_status_port},
                                   {"--grsim-yellow-status-port", grsim_yellow_status_port}}) {
    if (port < 1 || port > 65535) return fail(std::string(name) + " " + std::to_string(port) + " is not in 1..65535");
  }
  if (vision_port < 1 || vision_port > 65535) return fail("--vision-port " + std::to_string(vision_port) + " is not in 1..65535");
  if ((control_port != 0 && (control_port == blue_port || control_port == yellow_port)) ||
      (blue_port != 0 && blue_port == yellow_port))
    return fail("the control, blue and yellow ports must differ");
  if (!teams.empty() && !lockstep) return fail("--teams applies to --lockstep only");
  if (sync_port < -1 || sync_port > 65535) return fail("--sync-port " + std::to_string(sync_port) + " is not in 0..65535");
  if (sync_port >= 0 && lockstep) return fail("--sync-port sets its own pace (the client's requests); not with --lockstep");
  if (sync_port >= 0 && grsim_port >= 0) return fail("--grsim-port applies to the UDP interfaces, not --sync-port");
  if (receive_buffer > (1 << 30)) return fail("--receive-buffer is over 1 GB");
  if (sync_port >= 0 && (realtime_priority > 0 || cpu >= 0))
    return fail("--realtime-priority and --cpu apply to real time, not --sync-port");
  if (sync_team != "blue" && sync_team != "yellow") return fail("--sync-team: unknown team '" + sync_team + "' (known: blue, yellow)");
  for (const std::string& t : teams)
    if (t != "blue" && t != "yellow") return fail("--teams: unknown team '" + t + "' (known: blue, yellow)");
  if (receive_buffer < 0) return fail("--receive-buffer is negative");
  if (max_datagram < 64 || max_datagram > 65507) return fail("--max-datagram " + std::to_string(max_datagram) + " is not in 64..65507 bytes");
  if (!(max_rate >= 1 && max_rate <= 1e6)) return fail("--max-rate is not in 1..1e6 datagrams/s");
  if (!(geometry_period > 0 && geometry_period <= 3600)) return fail("--geometry-period is not in (0, 3600] s");
  if (!(boundary >= 0 && boundary <= 10)) return fail("--boundary is not in 0..10 m");
  if (max_frames < 0) return fail("--frames is negative");
  if (keep_frames < 0) return fail("keep_frames is negative");
  return true;
}

LiveField::LiveField(const Scene& scene, Simulation sim, const ServeOptions& options)
    : scene_(scene),
      sim_(std::move(sim)),
      options_(options),
      roster_([&] {
        std::vector<TeamRobot> robots;
        for (const SceneRobot& r : scene.robots)
          robots.push_back(TeamRobot{r.team == "yellow" ? TeamColor::kYellow : TeamColor::kBlue, r.id, WheelMapFor(r.model)});
        return robots;
      }()),
      control_(),
      teams_{TeamPort(TeamColor::kBlue), TeamPort(TeamColor::kYellow)} {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError(why);
  if (2 * options_.boundary >= std::min(scene.field.length, scene.field.width))
    throw InputError(SourceLocation{scene.path}, "--boundary " + std::to_string(options_.boundary) +
                                                     " m leaves no field inside the walls");
  if (sim_.num_robots() != roster_.size()) throw std::invalid_argument("LiveField: the simulation is not the scene's");
  vision_delay_ = sim_.robot_model(0).vision_delay_frames;
  for (int i = 1; i < sim_.num_robots(); ++i) {
    if (sim_.robot_model(i).vision_delay_frames != vision_delay_) {
      throw InputError(SourceLocation{scene.path},
                       "robots '" + sim_.robot_name(0) + "' and '" + sim_.robot_name(i) + "' have vision delays of " +
                           std::to_string(vision_delay_) + " and " +
                           std::to_string(sim_.robot_model(i).vision_delay_frames) +
                           " frames; twinsim serve's cameras share one delay");
    }
  }
  cameras_ = CameraRig(scene, sim_, vision_delay_);
  control_ = UdpSocket(options_.listen, options_.control_port);
  teams_[0].socket = UdpSocket(options_.listen, options_.blue_port);
  teams_[1].socket = UdpSocket(options_.listen, options_.yellow_port);
  // The kernel's default buffer (about 200 kB) drops a burst of a few hundred datagrams
  // before the loop reads them; the rate limit can only drop what reaches it.
  receive_buffer_asked_ = options_.receive_buffer > 0
                              ? options_.receive_buffer
                              : static_cast<int>(std::min(kMaxDefaultBuffer, options_.max_rate * kBufferedSeconds * kDatagramCost));
  receive_buffer_ = std::min({control_.SetReceiveBuffer(receive_buffer_asked_),
                              teams_[0].socket.SetReceiveBuffer(receive_buffer_asked_),
                              teams_[1].socket.SetReceiveBuffer(receive_buffer_asked_)});
  if (options_.sync_port >= 0) sync_.emplace(options_.listen, options_.sync_port);
  if (options_.grsim_port >= 0) {
    grsim_.emplace(options_.listen, options_.grsim_port);
    receive_buffer_ = std::min(receive_buffer_, grsim_->SetReceiveBuffer(receive_buffer_asked_));
  }
  for (const std::string& t : options_.teams) teams_[t == "blue" ? 0 : 1].waited = true;
  vision_to_ = UdpEndpoint{ParseIpv4(options_.vision_address), options_.vision_port};
  // A multicast group reaches every client on the network (and this host's own: loop),
  // as the league's SSL-Vision does; only when the user names one.
  if (IsMulticast(vision_to_.address))
    vision_out_.SetMulticastSender(options_.vision_ttl, /*loop=*/true, options_.vision_interface);
  moves_.resize(static_cast<std::size_t>(sim_.num_robots()));
  ball_commands_.resize(static_cast<std::size_t>(sim_.num_robots()));
  ball_driven_.assign(static_cast<std::size_t>(sim_.num_robots()), false);
  result_.backend = sim_.backend().name();
  result_.timing = sim_.backend().timing();
  for (int i = 0; i < sim_.num_robots(); ++i) {
    result_.robot_names.push_back(sim_.robot_name(i));
    result_.robot_backends.push_back(sim_.backend().robot_backend(i));
  }
  result_.frames.resize(static_cast<std::size_t>(sim_.num_robots()));
  if (options_.keep_frames > 0) {
    // All the memory the history will take, at once: nothing grows (or is copied) in the frame loop.
    const auto most = 2 * static_cast<std::size_t>(options_.keep_frames);
    for (auto& f : result_.frames) f.reserve(most);
    if (sim_.has_ball()) result_.ball.reserve(most);
  }
  control_tokens_ = grsim_tokens_ = teams_[0].tokens = teams_[1].tokens = options_.max_rate;
}

bool LiveField::TakeToken(double* tokens) {
  if (*tokens < 1) return false;
  *tokens -= 1;
  return true;
}

void LiveField::RefillTokens(double seconds) {
  for (double* tokens : {&teams_[0].tokens, &teams_[1].tokens, &control_tokens_, &grsim_tokens_})
    *tokens = std::min(options_.max_rate, *tokens + seconds * options_.max_rate);
}

bool LiveField::FrameComplete() const {
  bool any = false;
  for (const TeamPort& t : teams_) {
    if (!t.waited) continue;
    any = true;
    if (!t.answered) return false;
  }
  return any;
}

std::vector<SSL_WrapperPacket> LiveField::VisionPackets(const std::vector<FrameRecord>& records) {
  const int k = sim_.frame();
  const double dt = result_.timing.frame_dt();
  // Lockstep and the synchronous interface stamp simulated time (deterministic); real
  // time, Unix time as SSL-Vision: the wall clock when the frame captured began,
  // whatever the pace was since.
  double t_capture = (k - vision_delay_) * dt, t_sent = k * dt;
  if (!SimulatedTime()) {
    t_capture = FrameUnixTime(k - vision_delay_);
    t_sent = UnixNow();
  }
  // Asked again for the same frame (the synchronous interface, a request without a
  // step): the same packets, the cameras' noise not drawn twice.
  if (vision_frame_ == k) return vision_packets_;
  std::vector<SSL_WrapperPacket> packets;
  if (cameras_.empty()) {
    // One camera: what the observer receives.
    std::vector<Sighting> seen;
    for (int i = 0; i < sim_.num_robots(); ++i) {
      const FrameRecord& r = records[static_cast<std::size_t>(i)];
      if (r.observed) seen.push_back(Sighting{roster_.robot(i), r.seen});
    }
    std::optional<Eigen::Vector3d> ball;
    if (sim_.has_ball() && sim_.ball_record().observed) ball = sim_.ball_record().seen;
    packets.push_back(DetectionPacket(seen, static_cast<std::uint32_t>(k), t_capture, t_sent, ball));
  } else {
    const auto frame_time = [&](int j) { return SimulatedTime() ? j * dt : FrameUnixTime(j); };
    packets = cameras_.Packets(k, frame_time, t_sent, sim_, roster_);
  }
  // Geometry in the first packet at frame 0 and then every geometry_period.
  const int every = std::max(1, static_cast<int>(std::lround(options_.geometry_period / dt)));
  if (k % every == 0) *packets[0].mutable_geometry() = GeometryPacket(scene_.field, options_.boundary, cameras_.views()).geometry();
  vision_frame_ = k;
  vision_packets_ = packets;
  return packets;
}

void LiveField::SendVision(const std::vector<FrameRecord>& records) {
  for (const SSL_WrapperPacket& packet : VisionPackets(records)) {
    Send(vision_out_, packet.SerializeAsString(), vision_to_);
    ++counters_.vision_packets;
  }
}

double LiveField::FrameUnixTime(int frame) const {
  if (frame >= 0) return frame_unix_[static_cast<std::size_t>(frame) % frame_unix_.size()];
  // Before frame 0 the robots stood at their starts: stamped as if frames had run.
  return unix_start_ + frame * result_.timing.frame_dt();
}

void LiveField::Send(const UdpSocket& socket, const std::string& bytes, const UdpEndpoint& to) {
  if (socket.SendTo(bytes, to, &last_send_error_)) return;
  ++counters_.failed_sends;
}

void LiveField::Drain(int port) {
  if (port == 3 && !grsim_) return;
  const UdpSocket& socket = port == 3 ? *grsim_ : port == 2 ? control_ : teams_[static_cast<std::size_t>(port)].socket;
  for (int n = 0; n < kMaxDatagramsPerDrain; ++n) {
    std::optional<Datagram> d = socket.Receive(static_cast<std::size_t>(options_.max_datagram));
    if (!d) return;
    if (d->kernel_drops) {
      // The kernel's count is cumulative (and wraps at 2^32).
      std::uint32_t& seen = kernel_drops_[static_cast<std::size_t>(port)];
      counters_.kernel_dropped += static_cast<std::uint32_t>(*d->kernel_drops - seen);
      seen = *d->kernel_drops;
    }
    if (port == 3) {
      HandleGrSim(*d);
    } else if (port == 2) {
      HandleControl(*d);
    } else {
      HandleTeam(teams_[static_cast<std::size_t>(port)], *d);
    }
  }
}

void LiveField::HandleTeam(TeamPort& team, const Datagram& d) {
  if (!TakeToken(&team.tokens)) {
    ++counters_.rate_dropped;  // answering a flood would double it
    return;
  }
  const std::string port = std::string(TeamName(team.team)) + " port";
  if (d.truncated()) {
    ++counters_.oversized;
    RobotControlResponse r;
    AddError(&r, "TWINSIM_OVERSIZED", "a datagram of " + std::to_string(d.size) + " bytes on the " + port +
                                          " is over the limit of " + std::to_string(options_.max_datagram));
    Answer(team.socket, r, d.from);
    return;
  }
  if (options_.tournament && team.client && *team.client != d.from) {
    ++counters_.refused;
    RobotControlResponse r;
    AddError(&r, "TWINSIM_PORT_TAKEN", "tournament mode: the " + port + " is driven by " + team.client->ToString() +
                                           "; " + d.from.ToString() + " is refused");
    Answer(team.socket, r, d.from);
    return;
  }
  const RobotControlResult read = TakeRobotControl(team, d.bytes);
  if (!read.parsed) {
    ++counters_.malformed;
    Answer(team.socket, read.response, d.from);
    return;
  }
  team.client = d.from;
  const long long stored_ns = UnixNanos();
  timing_.command_latency.Add(1e-9 * static_cast<double>(stored_ns - d.arrival_ns));
  timing_.command_handling.Add(1e-9 * static_cast<double>(stored_ns - d.read_ns));
  if (!d.kernel_stamp) ++timing_.unstamped;
  Answer(team.socket, read.response, d.from);
}

RobotControlResult LiveField::TakeRobotControl(TeamPort& team, const std::string& bytes) {
  std::vector<bool> contact;
  if (sim_.has_ball())
    for (int i = 0; i < sim_.num_robots(); ++i) contact.push_back(sim_.ball()->contact(i));
  const std::vector<bool> present = Present();
  RobotControlResult read = ReadRobotControl(bytes, team.team, roster_, sim_.has_ball() ? &contact : nullptr, &present);
  if (!read.parsed) return read;
  ++counters_.robot_controls;
  counters_.refused += read.refused;
  team.waited = true;
  team.answered = true;
  for (const auto& [robot, move] : read.moves) moves_[static_cast<std::size_t>(robot)] = move;
  for (const auto& [robot, ball] : read.ball_commands) {
    ball_commands_[static_cast<std::size_t>(robot)] = ball;
    ball_driven_[static_cast<std::size_t>(robot)] = true;
  }
  return read;
}

SimulatorCommandResult LiveField::TakeSimulatorCommand(const std::string& bytes) {
  const std::vector<bool> present = Present();
  SimulatorCommandResult read = ReadSimulatorCommand(bytes, roster_, scene_.field, sim_.has_ball(), &present);
  if (!read.parsed) return read;
  ++counters_.simulator_commands;
  counters_.refused += read.refused;
  ApplyControl(read);
  if (read.simulation_speed) {
    if (SimulatedTime()) {
      ++counters_.refused;
      AddError(&read.response, "TWINSIM_UNSUPPORTED",
               "simulation_speed: in lockstep and the synchronous interface the clients set the pace");
    } else {
      speed_ = *read.simulation_speed;
    }
  }
  return read;
}

void LiveField::HandleGrSim(const Datagram& d) {
  // grSim answers nothing: what is refused is counted only (the summary).
  if (!TakeToken(&grsim_tokens_)) {
    ++counters_.rate_dropped;
    return;
  }
  if (d.truncated()) {
    ++counters_.oversized;
    return;
  }
  const GrSimPacket packet = ReadGrSimPacket(d.bytes, [this](TeamColor team, unsigned id) {
    const int robot = roster_.Find(team, id);
    return robot < 0 ? 0.0 : sim_.robot_model(robot).wheel_radius;
  });
  if (!packet.parsed) {
    ++counters_.malformed;
    return;
  }
  ++counters_.grsim_packets;
  if (packet.commands) {
    TeamPort& team = teams_[packet.team == TeamColor::kYellow ? 1 : 0];
    // Tournament mode: a team is driven from one address, over its own port or grSim's,
    // whichever it used first.
    if (options_.tournament && team.client && *team.client != d.from) {
      ++counters_.refused;
    } else if (TakeRobotControl(team, packet.commands->SerializeAsString()).parsed) {
      team.client = d.from;
      team.grsim_client = d.from;  // its robots' status goes there (never to a refused address)
    }
  }
  if (packet.replacement) {
    if (options_.tournament) {
      ++counters_.refused;  // as simulator control on the control port
    } else {
      TakeSimulatorCommand(packet.replacement->SerializeAsString());
    }
  }
}

void LiveField::HandleControl(const Datagram& d) {
  if (!TakeToken(&control_tokens_)) {
    ++counters_.rate_dropped;
    return;
  }
  SimulatorResponse response;
  if (d.truncated()) {
    ++counters_.oversized;
    AddError(&response, "TWINSIM_OVERSIZED", "a datagram of " + std::to_string(d.size) +
                                                 " bytes on the control port is over the limit of " +
                                                 std::to_string(options_.max_datagram));
    Answer(control_, response, d.from);
    return;
  }
  if (options_.tournament) {
    ++counters_.refused;
    AddError(&response, "TWINSIM_TOURNAMENT", "tournament mode: simulator control is refused");
    Answer(control_, response, d.from);
    return;
  }
  const SimulatorCommandResult read = TakeSimulatorCommand(d.bytes);
  if (!read.parsed) {
    ++counters_.malformed;
    Answer(control_, read.response, d.from);
    return;
  }
  control_client_ = d.from;
  Answer(control_, read.response, d.from);
}

std::vector<bool> LiveField::Present() const {
  std::vector<bool> present(static_cast<std::size_t>(sim_.num_robots()));
  for (int i = 0; i < sim_.num_robots(); ++i) present[static_cast<std::size_t>(i)] = sim_.present(i);
  return present;
}

void LiveField::ApplyControl(const SimulatorCommandResult& read) {
  for (const RobotTeleport& t : read.teleports) {
    const auto k = static_cast<std::size_t>(t.robot);
    if (t.present && !*t.present) {
      // Removed: the team's last move and ball command are forgotten, so that the robot
      // stands still when it is added again, until its team commands it.
      sim_.Remove(t.robot);
      moves_[k] = RobotMove{};
      ball_commands_[k] = BallCommand{};
      continue;
    }
    if (!sim_.present(t.robot)) {
      // Added: a coordinate left out is the scene start's (the parking spot means nothing).
      const Pose2 pose = TeleportedPose(t, scene_.robots[k].start);
      sim_.Add(t.robot, pose, FieldToBody(t.field_velocity, pose.theta));
      continue;
    }
    const Pose2 pose = TeleportedPose(t, sim_.backend().pose(t.robot));
    if (t.by_force) {
      sim_.PullRobot(t.robot, pose);
    } else {
      sim_.Teleport(t.robot, pose, FieldToBody(t.field_velocity, pose.theta));
    }
  }
  if (read.ball) {
    const BallState target = TeleportedBall(*read.ball, sim_.ball()->ball(), sim_.ball()->model().radius);
    if (read.ball->safely) MakeRoomForBall(target.position.head<2>());
    if (read.ball->by_force) {
      sim_.PullBall(target.position.head<2>());
    } else {
      sim_.TeleportBall(target);
    }
  }
  if (read.config.vision_port) vision_to_.port = *read.config.vision_port;
  if (read.config.ball_noise_xy || read.config.ball_drop) {
    BallVision vision = sim_.ball_vision();
    vision.noise_xy = read.config.ball_noise_xy.value_or(vision.noise_xy);
    vision.drop_probability = read.config.ball_drop.value_or(vision.drop_probability);
    sim_.SetBallVision(vision);
  }
  if (read.config.robot_noise_xy || read.config.robot_noise_theta) {
    for (int i = 0; i < sim_.num_robots(); ++i) {
      const VisionNoise& now = sim_.vision_noise(i);
      sim_.SetVisionNoise(i, read.config.robot_noise_xy.value_or(now.xy), read.config.robot_noise_theta.value_or(now.theta));
    }
  }
}

void LiveField::MakeRoomForBall(const Eigen::Vector2d& target) {
  const double clearance = sim_.ball()->model().radius + kBallMargin;
  for (int i = 0; i < sim_.num_robots(); ++i) {
    if (!sim_.present(i)) continue;
    const Pose2 pose = sim_.backend().pose(i);
    const std::optional<Eigen::Vector2d> move = BallClearance(sim_.robot_model(i), pose, target, clearance);
    if (!move) continue;
    // Moved as a referee's hand moves it, keeping its velocity (robot frame).
    sim_.Teleport(i, Pose2{pose.x + move->x(), pose.y + move->y(), pose.theta}, sim_.backend().velocity(i));
  }
}

void LiveField::Record(const std::vector<FrameRecord>& records) {
  if (sink_) sink_(records, sim_.has_ball() ? &sim_.ball_record() : nullptr);
  if (counters_.frames % keep_stride_ != 0) return;
  for (std::size_t k = 0; k < records.size(); ++k) result_.frames[k].push_back(records[k]);
  if (sim_.has_ball()) result_.ball.push_back(sim_.ball_record());
  const auto kept = static_cast<long long>(result_.frames.empty() ? result_.ball.size() : result_.frames[0].size());
  if (options_.keep_frames == 0 || kept < 2LL * options_.keep_frames) return;
  // Full: every other frame kept goes, and from now on every other is kept.
  auto thin = [](auto& v) {
    for (std::size_t i = 0; 2 * i < v.size(); ++i) v[i] = v[2 * i];
    v.resize((v.size() + 1) / 2);
  };
  for (auto& f : result_.frames) thin(f);
  thin(result_.ball);
  keep_stride_ *= 2;
}

ServeSummary LiveField::Summary() const {
  ServeSummary s;
  s.counters = counters_;
  s.timing = timing_;
  s.simulated = static_cast<double>(counters_.frames) * result_.timing.frame_dt();
  s.wall = Seconds(Clock::now() - start_);
  for (std::size_t t = 0; t < 2; ++t)
    if (teams_[t].client) s.clients[t] = teams_[t].client->ToString();
  s.receive_buffer_asked = receive_buffer_asked_;
  s.receive_buffer = receive_buffer_;
  s.last_send_error = last_send_error_;
  return s;
}

ServeSummary LiveField::Run(const std::function<bool()>& stop, const std::function<void(const ServeSummary&)>& status) {
  if (sync_) return RunSync(stop, status);
  const RealtimeScope realtime(options_.realtime_priority, options_.cpu);
  start_ = last_refill_ = Clock::now();
  unix_start_ = UnixNow();
  frame_unix_.assign(static_cast<std::size_t>(vision_delay_) + 2, unix_start_);
  Clock::time_point frame_end = start_, next_status = start_;
  const double dt = result_.timing.frame_dt();
  std::vector<const UdpSocket*> sockets{&teams_[0].socket, &teams_[1].socket, &control_};
  if (grsim_) sockets.push_back(&*grsim_);
  // The serving CPU's accounting, of the CPU the thread runs on at each reading.
  const CpuTime cpu;
  Usage worked = UsageNow(cpu);  // at the end of the last frame's work
  while (!stop() && (options_.max_frames == 0 || counters_.frames < options_.max_frames)) {
    const Usage started = UsageNow(cpu);
    const Clock::time_point frame_start = Clock::now();
    if (!options_.lockstep) {
      const double lateness = Seconds(frame_start - frame_end);
      timing_.start_lateness.Add(lateness);
      if (lateness > timing_.latest_start.seconds) {
        timing_.latest_start = StallOf(counters_.frames, lateness, 0, cpu, {{worked, started}});
        timing_.latest_start.woke_late = woke_late_;
      }
      frame_unix_[static_cast<std::size_t>(sim_.frame()) % frame_unix_.size()] = UnixNow();
    }
    std::vector<FrameRecord> records = OpenFrame();
    SendVision(records);
    const Clock::duration vision_work = Clock::now() - frame_start;
    const Usage sent = UsageNow(cpu);
    for (TeamPort& t : teams_) t.answered = false;
    if (!options_.lockstep) {
      frame_end += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(dt / speed_));
      if (Clock::now() > frame_end) {
        ++counters_.late_frames;
        frame_end = Clock::now();
      }
    }
    if (options_.lockstep) RefillTokens(dt);
    if (AwaitFrameEnd(frame_end, sockets, stop, status, &next_status)) break;  // stopped: not logged, no commands
    const Usage stepping = UsageNow(cpu);
    const Clock::time_point step_start = Clock::now();
    FinishFrame(&records);
    const double work = Seconds(vision_work + (Clock::now() - step_start));
    timing_.frame_work.Add(work);
    worked = UsageNow(cpu);
    if (work > timing_.slowest.seconds)
      timing_.slowest =
          StallOf(counters_.frames - 1, work, Seconds(vision_work), cpu, {{started, sent}, {stepping, worked}});
  }
  return Summary();
}

bool LiveField::AwaitFrameEnd(std::chrono::steady_clock::time_point frame_end,
                              const std::vector<const UdpSocket*>& sockets, const std::function<bool()>& stop,
                              const std::function<void(const ServeSummary&)>& status,
                              std::chrono::steady_clock::time_point* next_status) {
  Clock::time_point resend = Clock::now() + std::chrono::milliseconds(static_cast<int>(1000 * kResendPeriod));
  woke_late_ = 0;
  for (;;) {
    if (stop()) return true;
    if (options_.lockstep && FrameComplete()) return false;
    const Clock::time_point now = Clock::now();
    double wait = kPollPeriod;
    if (!options_.lockstep) {
      const double left = Seconds(frame_end - now);
      if (left <= 0) return false;
      wait = std::min(wait, left);
    }
    // The rate limit's buckets fill at max_rate per second of wall time, up to one
    // second's worth; in lockstep, which runs as fast as the clients answer, also per
    // second of simulated time (at each frame's start).
    RefillTokens(Seconds(now - last_refill_));
    last_refill_ = now;
    const bool readable = WaitReadable(sockets, wait) >= 0;
    woke_late_ = std::max(0.0, Seconds(Clock::now() - now) - wait);
    if (readable)
      for (int port = 0; port < 4; ++port) Drain(port);
    // Lockstep: a team yet to come may have missed this frame's vision, and a team
    // waited for may have had its answer lost (dropped over the rate limit, or by the
    // network): the frame's vision again, which a client answers as it answers any.
    if (options_.lockstep && Clock::now() >= resend) {
      if (!FrameComplete()) {
        for (const SSL_WrapperPacket& packet : vision_packets_) {
          Send(vision_out_, packet.SerializeAsString(), vision_to_);
          ++counters_.vision_packets;
        }
      }
      resend = Clock::now() + std::chrono::milliseconds(static_cast<int>(1000 * kResendPeriod));
    }
    if (status && Clock::now() >= *next_status) {
      status(Summary());
      *next_status = Clock::now() + std::chrono::milliseconds(100);
    }
  }
}

std::vector<FrameRecord> LiveField::OpenFrame() {
  std::vector<FrameRecord> records = sim_.BeginFrame();
  cameras_.Record(sim_.frame(), records, sim_);
  return records;
}

void LiveField::FinishFrame(std::vector<FrameRecord>* records) {
  // A robot no team has commanded yet follows its scene's source, kicks included.
  std::vector<BallCommand> ball_commands = ball_commands_;
  for (int i = 0; i < sim_.num_robots(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!sim_.present(i)) continue;  // off the field: sent nothing, its behaviour not asked
    (*records)[k].command = moves_[k] ? LocalVelocity(*moves_[k], (*records)[k].truth.theta) : sim_.SourceCommand(i);
    if (sim_.has_ball() && !ball_driven_[k]) ball_commands[k] = sim_.SourceBallCommand(i);
  }
  sim_.EndFrame(records, ball_commands);
  for (BallCommand& c : ball_commands_) c.kick_speed = 0;  // a kick is for its frame
  Record(*records);
  ++counters_.frames;
  if (grsim_) SendGrSimStatus();
}

void LiveField::SendGrSimStatus() {
  grsim_status_.resize(static_cast<std::size_t>(sim_.num_robots()), -1);
  for (TeamPort& team : teams_) {
    if (!team.grsim_client) continue;
    Robots_Status status;
    for (int i = 0; i < sim_.num_robots(); ++i) {
      if (roster_.robot(i).team != team.team) continue;
      const bool infrared = sim_.has_ball() && sim_.ball()->contact(i);
      const int kick = sim_.has_ball() ? sim_.ball()->kicked(i) : 0;
      const int now = (infrared ? 1 : 0) + (kick == 1 ? 2 : 0) + (kick == 2 ? 4 : 0);
      int& sent = grsim_status_[static_cast<std::size_t>(i)];
      if (now == sent) continue;
      sent = now;
      Robot_Status* r = status.add_robots_status();
      r->set_robot_id(roster_.robot(i).id);
      r->set_infrared(infrared);
      r->set_flat_kick(kick == 1);
      r->set_chip_kick(kick == 2);
    }
    if (status.robots_status_size() == 0) continue;
    UdpEndpoint to = *team.grsim_client;
    to.port = team.team == TeamColor::kYellow ? options_.grsim_yellow_status_port : options_.grsim_blue_status_port;
    Answer(*grsim_, status, to);
  }
}

}  // namespace twinsim
