// A scene's field served live over the league's network protocol (twinsim serve,
// docs/serve.md): teams drive their robots with RobotControl on their ports (or grSim's
// packets on grSim's port), a controller moves robots with SimulatorCommand, and every
// camera frame the field sends the SSL-Vision packet of what the observer receives,
// through the scene's delay loop and camera noise (sim/omni_simulation.h), or with a
// scene's `cameras:` one packet per camera of what it sees. The synchronous interface
// (sync_port, serve/sync_interface.cc) steps the field on a TCP client's requests instead.
//
// Per camera frame k: BeginFrame (capture, vision delay) -> send the detection of frame
// k -> take commands until the frame ends -> EndFrame (command delay, physics). A frame
// ends
//   - in lockstep, when every team waited for (those named, and every team that has
//     sent a RobotControl) has sent one since the frame's vision went out; until then
//     the frame's vision goes out again every 0.25 s (a client started late, an
//     answer lost);
//   - in real time, at the wall-clock time of the next frame (x the simulation speed).
// So a command sent in answer to the vision of frame k is logged in frame k and first
// moves the robots seen in frame k + D + 1 (D = command + vision delay), as in
// `twinsim run`. A robot keeps the last move it received; a robot no team has
// commanded yet follows its scene's `commands`.
//
//   LiveField field(scene, MakeSimulation(scene, "analytic"), options);
//   ServeSummary summary = field.Run([] { return InterruptSignal() != 0; });
//   WriteOmniRunFiles(scene, field.result(), true, &files);
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/duration_histogram.h"
#include "core/rng.h"
#include "scene/camera_layout.h"
#include "scene/scene.h"
#include "serve/camera_rig.h"
#include "serve/robot_control.h"
#include "serve/simulator_control.h"
#include "serve/team_roster.h"
#include "serve/tcp_stream.h"
#include "serve/udp_socket.h"
#include "sim/omni_simulation.h"
#include "ssl_vision_wrapper.pb.h"

namespace twinsim {

struct ServeOptions {
  std::string listen = "127.0.0.1";  // the address the ports listen on
  int control_port = 10300;          // SimulatorCommand; 0: any free port
  int blue_port = 10301;             // blue team's RobotControl
  int yellow_port = 10302;           // yellow team's RobotControl
  int grsim_port = -1;               // grSim's protocol (serve/grsim_packet.h): -1 off; 0 any free port; grSim's is 20011
  // grSim's robot status (Robots_Status: infrared, flat and chip kick per robot), sent with
  // the grSim port to the address a team's last grSim packet came from, at these ports
  // (grSim's defaults); each frame in which a robot's status changed, with those robots.
  int grsim_blue_status_port = 30011;
  int grsim_yellow_status_port = 30012;
  // The synchronous interface (TCP, ssl_simulation_synchronous.proto): -1 off; 0 any
  // free port. On, the field steps only when its one client asks (no UDP is read or sent).
  int sync_port = -1;
  std::string sync_team = "blue";    // the team a synchronous request's RobotControl commands
  std::string vision_address = "127.0.0.1";  // SSL_WrapperPacket go here (unicast, or a multicast group)
  int vision_port = 10020;
  int vision_ttl = 1;                 // multicast vision: hops (1: this network only)
  std::string vision_interface;       // multicast vision: leave by the interface of this address; empty: the route's
  // Real time: the serving thread's SCHED_FIFO priority (1..99; 0: the normal
  // scheduler) and the CPU it is pinned to (-1: any), so that other work on the host
  // does not delay a frame or a command (docs/serve.md "How fast").
  int realtime_priority = 0;
  int cpu = -1;
  bool lockstep = false;              // false: real time
  std::vector<std::string> teams;     // lockstep: teams waited for from frame 0 ("blue", "yellow")
  bool tournament = false;            // refuse simulator control; one address per team port
  int max_datagram = 8192;            // bytes; a larger datagram is refused
  // bytes of each port's receive buffer (the kernel's accounting); 0: enough for a
  // quarter of a second at max_rate (kBufferedSeconds). Beyond net.core.rmem_max only
  // with CAP_NET_ADMIN; the summary says what the kernel granted.
  int receive_buffer = 0;             // (at most 1 GB)
  double max_rate = 1000;             // datagrams/s per port (lockstep: also per simulated s); beyond, dropped unanswered
  double geometry_period = 1;         // s of simulated time between geometry packets
  double boundary = 0.3;              // m between the walls and the field lines
  long long max_frames = 0;           // stop after this many frames; 0: when stopped
  // Frames result() keeps per robot: 0, every one; else a thinned history for the plots
  // of at least this many and fewer than twice as many (every 2^j-th frame, the whole
  // match at an even pace), so that memory stays flat however long the match (the logs
  // go to a frame sink as the match runs: SetFrameSink, scene/run_log_stream.h).
  int keep_frames = 0;

  // False (with the reason in *why) for values out of range, an address that is not
  // IPv4, multicast options for a unicast vision address, an unknown team name.
  bool IsValid(std::string* why) const;
};

// What happened, counted.
struct ServeCounters {
  long long frames = 0;
  long long vision_packets = 0;      // sent (detections and geometry)
  long long robot_controls = 0;      // RobotControl read
  long long simulator_commands = 0;  // SimulatorCommand read
  long long grsim_packets = 0;       // grSim_Packet read
  long long sync_requests = 0;       // SimulationSyncRequest read
  long long refused = 0;             // robot commands and control requests refused (answered)
  long long malformed = 0;           // datagrams that were no message (answered)
  long long oversized = 0;           // datagrams over the size limit (answered)
  long long rate_dropped = 0;        // datagrams over the rate limit (dropped)
  long long late_frames = 0;         // real time: frames that started after their time
  long long kernel_dropped = 0;      // datagrams the kernel dropped, its receive buffer full (as far as seen)
  long long failed_sends = 0;        // vision packets and answers the system refused to send
};

// How long the loop took, on the wall clock (bench/serve_bench.cc, docs/benchmarks.md).
// Recording it allocates nothing and changes nothing the field does.
struct ServeTiming {
  // s per frame run: capturing and sending its vision, then stepping its commands
  // through the delay line and physics and logging it (the waiting for commands left out).
  DurationHistogram frame_work{50e-6, 1000};
  // s per frame, real time only: how much later than its time on the wall clock (the
  // end of the frame before) the frame began.
  DurationHistogram start_lateness{50e-6, 1000};
  // s per RobotControl read: from its datagram's arrival (the kernel's receive stamp) to
  // its moves and ball commands stored for the next step, which pushes them into the
  // delay line.
  DurationHistogram command_latency{1e-6, 5000};
  // s per RobotControl read: the part of command_latency after the loop read the
  // datagram (parsing, checking, storing); the rest is the datagram waiting to be read.
  DurationHistogram command_handling{1e-6, 5000};
  long long unstamped = 0;  // of those, arrivals without a kernel stamp (the time recv returned)
  // The frame whose work took longest, and the frame that began latest, each with what
  // the kernel did to the serving thread meanwhile (getrusage per thread): a stall with
  // major faults waited for the disk, one with involuntary switches was preempted, one
  // with neither ran its own code (or, for a late start, waited in the kernel to wake).
  struct Stall {
    long long frame = -1;      // its index, -1 none yet
    double seconds = 0;        // s: the frame's work (slowest), or how late it began (latest_start)
    double vision = 0;         // slowest: s of the work capturing and sending the vision
    double woke_late = 0;      // latest_start: s the last wait for datagrams returned after its time
    long minor_faults = 0;     // page faults served without I/O
    long major_faults = 0;     // page faults that read from disk
    long voluntary = 0;        // context switches the thread asked for (a blocking call)
    long involuntary = 0;      // context switches forced on it (preemption)
    // s the hypervisor ran something else on the serving thread's CPU (steal time), and s
    // that CPU spent in interrupts, meanwhile: /proc/stat's 10 ms ticks; -1 unknown (no
    // /proc/stat, or the thread moved to another CPU: serve/cpu_time.h).
    double stolen = -1;
    double interrupts = -1;
    std::string Brief() const;
  };
  Stall slowest;       // over the frame's work
  Stall latest_start;  // over the wait before the frame (real time), from the last frame's work on
};

struct ServeSummary {
  ServeCounters counters;
  ServeTiming timing;
  double simulated = 0;  // s
  double wall = 0;       // s
  std::array<std::string, 2> clients;  // blue, yellow: the address that last sent, "" none
  int receive_buffer_asked = 0;        // bytes, per port
  int receive_buffer = 0;             // (at most 1 GB)              // bytes, per port: what the kernel granted (the smallest)
  std::string last_send_error;         // why the last refused send was refused
  // "1234 frames (41.1 s simulated) in 41.2 s wall; blue 127.0.0.1:5000, yellow -; 0 refused".
  std::string Brief() const;
  // Every counter, one per line, and the timing's quantiles.
  std::string Report() const;
};

class LiveField {
 public:
  // Opens the ports (throws InputError naming an address that cannot be bound) for
  // `sim`, built from `scene` (robots' teams and ids, field). Throws InputError when
  // the options are not valid or the robots' vision delays differ (the cameras share one delay).
  LiveField(const Scene& scene, Simulation sim, const ServeOptions& options);

  // The loop looks for a stop (and, in the synchronous interface, a client) this often
  // while it waits.
  static constexpr double kPollPeriod = 0.05;  // s
  // teleport_safely leaves at least this much between the ball and every chassis.
  static constexpr double kBallMargin = 0.02;  // m
  // The default receive buffer holds this long at max_rate, at kDatagramCost bytes of
  // the kernel's accounting per datagram (a RobotControl of 11 robots, about 400 bytes,
  // costs about 1.3 kB on loopback; a 2 kB one 3 kB).
  static constexpr double kBufferedSeconds = 0.25;  // s
  static constexpr int kDatagramCost = 3072;        // bytes
  static constexpr double kMaxDefaultBuffer = 16 << 20;  // bytes: the default's cap, whatever the rate

  int control_port() const { return control_.port(); }
  int blue_port() const { return teams_[0].socket.port(); }
  int yellow_port() const { return teams_[1].socket.port(); }
  int grsim_port() const { return grsim_ ? grsim_->port() : -1; }
  int sync_port() const { return sync_ ? sync_->port() : -1; }
  // bytes per port: the receive buffer asked for, and what the kernel granted.
  int receive_buffer_asked() const { return receive_buffer_asked_; }
  int receive_buffer() const { return receive_buffer_; }

  // Called with every frame run, as it ends: the records per robot and the ball's (null
  // without a ball). What it throws ends Run.
  using FrameSink = std::function<void(const std::vector<FrameRecord>&, const BallRecord*)>;
  void SetFrameSink(FrameSink sink) { sink_ = std::move(sink); }

  // Runs frames until `stop()` returns true (asked between datagrams and frames) or
  // max_frames have run; `status(summary)` is called about ten times a second. Throws
  // CheckFailed when the simulation diverges.
  ServeSummary Run(const std::function<bool()>& stop,
                   const std::function<void(const ServeSummary&)>& status = {});

  // Every frame run (thinned with keep_frames), for the logs and plots
  // (scene/scene_run.h: WriteOmniRunFiles).
  const SimulationResult& result() const { return result_; }
  // The simulation served (for tests: who is on the field, where the robots are).
  const Simulation& simulation() const { return sim_; }
  // The scene's cameras (none: one camera, sending what the observer receives).
  const std::vector<CameraView>& cameras() const { return cameras_.views(); }
  // Where vision goes now (--vision-port, or SimulatorConfig.vision_port).
  const UdpEndpoint& vision_to() const { return vision_to_; }

 private:
  struct TeamPort {
    explicit TeamPort(TeamColor color) : team(color) {}
    TeamColor team;
    UdpSocket socket;
    bool waited = false;                   // lockstep: named, or has sent a RobotControl
    bool answered = false;                 // has sent since this frame's vision
    std::optional<UdpEndpoint> client;     // tournament: the one address allowed; else the last
    std::optional<UdpEndpoint> grsim_client;  // where its last grSim packet came from (its status goes there)
    double tokens = 0;                     // rate limit
  };

  // Each camera's detection (and the geometry, at its period) of the open frame, whose
  // records BeginFrame gave, kept for the frame (vision_packets_); SendVision sends them.
  std::vector<SSL_WrapperPacket> VisionPackets(const std::vector<FrameRecord>& records);
  void SendVision(const std::vector<FrameRecord>& records);
  // Begins a frame (the cameras' capture kept); steps the open frame with the commands
  // in force and logs it.
  std::vector<FrameRecord> OpenFrame();
  void FinishFrame(std::vector<FrameRecord>* records);
  // Reads what arrives until the frame's end (real time) or every team's answer
  // (lockstep), resending the vision in lockstep and calling `status` every 100 ms; true
  // when `stop` asked to stop. woke_late_ receives how late its last wait returned.
  bool AwaitFrameEnd(std::chrono::steady_clock::time_point frame_end, const std::vector<const UdpSocket*>& sockets,
                     const std::function<bool()>& stop, const std::function<void(const ServeSummary&)>& status,
                     std::chrono::steady_clock::time_point* next_status);
  // The synchronous interface: the frames run as the client's requests ask.
  ServeSummary RunSync(const std::function<bool()>& stop, const std::function<void(const ServeSummary&)>& status);
  // Answers one request; false when the answer could not be written whole.
  bool HandleSyncRequest(const std::string& bytes, std::vector<FrameRecord>* records, TcpConnection* client);
  // Vision stamped with simulated time (lockstep, synchronous), else Unix time.
  bool SimulatedTime() const { return options_.lockstep || sync_.has_value(); }
  // Sends, counting a refused send (failed_sends, last_send_error).
  void Send(const UdpSocket& socket, const std::string& bytes, const UdpEndpoint& to);
  template <typename Message>
  void Answer(const UdpSocket& socket, const Message& message, const UdpEndpoint& to) {
    Send(socket, message.SerializeAsString(), to);
  }
  // The Unix time (s) at which `frame` began on the wall clock, as far back as the
  // vision delay and a frame before it go: the capture times of the vision.
  double FrameUnixTime(int frame) const;
  // Reads every datagram waiting on the socket at `port` (0, 1 teams, 2 control, 3 grSim).
  void Drain(int port);
  void HandleTeam(TeamPort& team, const Datagram& d);
  void HandleControl(const Datagram& d);
  void HandleGrSim(const Datagram& d);
  // grSim's robot status after a frame: to each team that sent grSim packets, its robots
  // whose infrared (the ball at the dribbler) or kick changed (grsim_status_).
  void SendGrSimStatus();
  // Applies a RobotControl `team` sent (as bytes), read and checked; returns the read.
  RobotControlResult TakeRobotControl(TeamPort& team, const std::string& bytes);
  // Applies a SimulatorCommand (as bytes), read and checked; returns the read, its
  // response with the errors of what was refused (and counted).
  SimulatorCommandResult TakeSimulatorCommand(const std::string& bytes);
  // Applies what a SimulatorCommand asked for and the reader accepted.
  void ApplyControl(const SimulatorCommandResult& read);
  // teleport_safely: moves every robot on the field whose chassis would be within
  // kBallMargin of a ball at `target` (m, field frame) the shortest way out of it.
  void MakeRoomForBall(const Eigen::Vector2d& target);
  // Per robot index: on the field now.
  std::vector<bool> Present() const;
  bool TakeToken(double* tokens);
  // Adds `seconds` worth of max_rate to every port's bucket (at most one second's worth).
  void RefillTokens(double seconds);
  bool FrameComplete() const;
  // Hands frame `records` (just run) to the sink and keeps it in result_ (thinned).
  void Record(const std::vector<FrameRecord>& records);
  ServeSummary Summary() const;

  const Scene& scene_;
  Simulation sim_;
  ServeOptions options_;
  TeamRoster roster_;
  UdpSocket control_;
  std::array<TeamPort, 2> teams_;
  std::optional<UdpEndpoint> control_client_;
  double control_tokens_ = 0;
  std::optional<UdpSocket> grsim_;  // grSim's protocol, when asked for
  std::optional<TcpListener> sync_;  // the synchronous interface, when asked for
  double grsim_tokens_ = 0;
  std::vector<int> grsim_status_;  // per robot, the status last sent: infrared + 2 flat + 4 chip (-1: never)
  UdpSocket vision_out_;
  UdpEndpoint vision_to_;
  int vision_delay_ = 0;                               // frames, every robot's
  std::vector<std::optional<RobotMove>> moves_;        // per robot; none: its scene's commands
  // Per robot, what it does to the ball: the dribbler holds until the robot's next
  // command, a kick counts for the frame it was sent in.
  std::vector<BallCommand> ball_commands_;
  std::vector<bool> ball_driven_;  // per robot: a team has sent it a kick or dribbler (else its scene's source)
  double speed_ = 1;                                   // real time x this
  ServeCounters counters_;
  ServeTiming timing_;
  SimulationResult result_;
  FrameSink sink_;
  long long keep_stride_ = 1;  // keep_frames: result_ keeps the frames whose number is a multiple of this
  std::chrono::steady_clock::time_point start_, last_refill_;
  double woke_late_ = 0;  // s: how much later than asked the last wait for datagrams returned
  double unix_start_ = 0;  // s, real time: the Unix time of frame 0
  // s, real time: the Unix time each of the last vision_delay + 2 frames began (frame k
  // at k % size), the capture times of the vision they send later.
  std::vector<double> frame_unix_;
  std::array<std::uint32_t, 4> kernel_drops_{};  // per port (blue, yellow, control, grSim): the kernel's count seen last
  std::string last_send_error_;
  int receive_buffer_asked_ = 0, receive_buffer_ = 0;  // bytes
  // The current frame's packets (one per camera): what a lockstep resend sends again and
  // what a synchronous request for the same frame gets.
  int vision_frame_ = -1;  // the frame vision_packets_ are of (-1: none yet)
  std::vector<SSL_WrapperPacket> vision_packets_;
  // Several cameras (the scene's `cameras:`; none: one, sending what the observer
  // receives).
  CameraRig cameras_;
};

}  // namespace twinsim
