// twinsim serve on the loopback, timed on the wall clock (issue 32; docs/benchmarks.md
// "twinsim serve (issue 32)"). A plain program rather than a Google Benchmark: each
// part is one run of a served field for seconds of wall time.
//
//   build/serve_bench                      # 20 s real time, 20000 lockstep frames
//   build/serve_bench --seconds 60 --lockstep-frames 60000
//   build/serve_bench --realtime-priority 50 --cpu 1   # as twinsim serve's options
//   build/serve_bench --memory-minutes 120              # part 4 alone: a 2 h match's memory
//   build/serve_bench --cameras 2 2                      # part 1 seen by four cameras
//   build/serve_bench --seconds 7200 --stream --realtime-priority 50 --cpu 1   # a 2 h match, logs streamed
//
// 1. Real time: scenes/serve_11v11.yaml (11 blue against 11 yellow and the ball) on ODE
//    at 60 fps, with one client thread per team that answers every vision packet with a
//    RobotControl for its 11 robots (each drives a 0.4 m circle). Frames run, late
//    frames, and histograms of each frame's work (vision, then commands through the
//    delay line, physics and the log) and of how late each frame began.
// 2. Latency, from the same run: from a RobotControl datagram's arrival (the kernel's
//    SO_TIMESTAMPNS receive stamp) to its moves stored for the delay line.
// 3. Lockstep throughput: one blue and one yellow robot on the analytic backend, a
//    client thread per team answering each vision packet at once; simulated seconds per
//    wall second.
//    Then the synchronous interface (TCP): one client stepping a frame per request.
// 4. Memory over a long match (`--memory-minutes M`, alone): serve_11v11 in lockstep on
//    analytic with the two clients, the logs streamed to a temporary folder as twinsim
//    serve writes them (scene/run_log_stream.h) and the thinned history for the plots;
//    the resident memory (VmRSS) every simulated minute. `--keep-all` keeps every frame
//    in memory instead, as serve did before.
// Everything on 127.0.0.1 with ports the system picks; never a multicast group.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/duration_histogram.h"
#include "scene/run_log_stream.h"
#include "scene/scene.h"
#include "serve/live_field.h"
#include "serve/udp_socket.h"
#include "serve/tcp_stream.h"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_simulation_synchronous.pb.h"

namespace twinsim {
namespace {

using Clock = std::chrono::steady_clock;

std::string Source(const std::string& path) { return std::string(TWINSIM_SOURCE_DIR) + "/" + path; }

UdpEndpoint Loopback(int port) { return UdpEndpoint{ParseIpv4("127.0.0.1"), port}; }

// Reads the vision packets sent to its port and wakes every team client on each.
class VisionReader {
 public:
  VisionReader() : socket_("127.0.0.1", 0), thread_([this] { Loop(); }) {}
  ~VisionReader() {
    stop_ = true;
    thread_.join();
  }
  int port() const { return socket_.port(); }
  // Waits at most `timeout` s for a packet after the `seen`-th; returns the packets so far.
  long long WaitAfter(long long seen, double timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, std::chrono::duration<double>(timeout), [&] { return packets_ > seen || stop_; });
    return packets_;
  }

 private:
  void Loop() {
    while (!stop_) {
      if (WaitReadable({&socket_}, 0.05) < 0) continue;
      long long n = 0;
      while (socket_.Receive(65536)) ++n;
      if (n == 0) continue;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        packets_ += n;
      }
      cv_.notify_all();
    }
    cv_.notify_all();
  }

  UdpSocket socket_;
  std::mutex mutex_;
  std::condition_variable cv_;
  long long packets_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A team's software in miniature: answers every vision packet with one RobotControl
// moving each of its robots on a circle (0.4 m/s forward, 1 rad/s), and reads the
// answers. In lockstep it sends its last command again after `resend` s without new
// vision (a datagram lost on the way).
class TeamClient {
 public:
  TeamClient(VisionReader* vision, int port, const std::vector<int>& ids, double resend)
      : vision_(vision), to_(Loopback(port)), resend_(resend) {
    RobotControl control;
    for (int id : ids) {
      RobotCommand* c = control.add_robot_commands();
      c->set_id(static_cast<unsigned>(id));
      MoveLocalVelocity* m = c->mutable_move_command()->mutable_local_velocity();
      m->set_forward(0.4f);
      m->set_left(0.0f);
      m->set_angular(1.0f);
    }
    command_ = control.SerializeAsString();
    thread_ = std::thread([this] { Loop(); });
  }
  ~TeamClient() {
    stop_ = true;
    thread_.join();
  }
  long long sent() const { return sent_; }
  long long resent() const { return resent_; }
  long long answers() const { return answers_; }

 private:
  void Loop() {
    long long seen = 0;
    while (!stop_) {
      const long long now = vision_->WaitAfter(seen, resend_ > 0 ? resend_ : 0.05);
      if (now > seen || (resend_ > 0 && sent_ > 0)) {
        if (now == seen) ++resent_;
        seen = now;
        if (socket_.SendTo(command_, to_)) ++sent_;
      }
      while (socket_.Receive(65536)) ++answers_;
    }
  }

  VisionReader* vision_;
  UdpEndpoint to_;
  double resend_;
  UdpSocket socket_{"127.0.0.1", 0};
  std::string command_;
  std::atomic<bool> stop_{false};
  std::atomic<long long> sent_{0}, resent_{0}, answers_{0};
  std::thread thread_;
};

std::vector<int> TeamIds(const Scene& scene, const std::string& team) {
  std::vector<int> ids;
  for (const SceneRobot& r : scene.robots)
    if (r.team == team) ids.push_back(r.id);
  return ids;
}

struct Served {
  ServeSummary summary;
  long long sent[2] = {0, 0}, resent[2] = {0, 0}, answers[2] = {0, 0};
};

// Serves `scene` on `backend` with a client per team until `frames` frames have run;
// `setup(field)` before it starts, `status(summary)` now and then while it runs.
Served Serve(const Scene& scene, const std::string& backend, ServeOptions options, long long frames, double resend,
             const std::function<void(LiveField*)>& setup = {},
             const std::function<void(const ServeSummary&)>& status = {}) {
  VisionReader vision;
  options.control_port = options.blue_port = options.yellow_port = 0;
  options.vision_port = vision.port();
  options.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, backend), options);
  if (setup) setup(&field);
  Served out;
  {
    TeamClient blue(&vision, field.blue_port(), TeamIds(scene, "blue"), resend);
    TeamClient yellow(&vision, field.yellow_port(), TeamIds(scene, "yellow"), resend);
    out.summary = field.Run([] { return false; }, status);
    const TeamClient* clients[2] = {&blue, &yellow};
    for (int t = 0; t < 2; ++t) {
      out.sent[t] = clients[t]->sent();
      out.resent[t] = clients[t]->resent();  // before the clients time out on a field that ended
    }
    // Answers still in flight to the clients.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    for (int t = 0; t < 2; ++t) out.answers[t] = clients[t]->answers();
  }
  return out;
}

// Rows of a histogram between `edges` (s), shown in `unit` (1e-3: ms, 1e-6: µs).
void PrintHistogram(const char* title, const DurationHistogram& h, const std::vector<double>& edges, double unit,
                    const char* unit_name) {
  std::printf("  %s: %s\n", title, h.Brief().c_str());
  std::printf("    %-22s %8s %8s\n", (std::string("bin, ") + unit_name).c_str(), "count", "cum. %");
  long long cumulative = 0;
  for (std::size_t i = 0; i + 1 <= edges.size(); ++i) {
    const double from = edges[i], to = i + 1 < edges.size() ? edges[i + 1] : 1e9;
    const long long n = h.CountBetween(from, to);
    cumulative += n;
    if (n == 0 && (cumulative == 0 || cumulative == h.count())) continue;
    char bin[64];
    if (i + 1 < edges.size()) {
      std::snprintf(bin, sizeof bin, "[%g, %g)", from / unit, to / unit);
    } else {
      std::snprintf(bin, sizeof bin, ">= %g", from / unit);
    }
    std::printf("    %-22s %8lld %7.2f%%\n", bin, n, 100.0 * static_cast<double>(cumulative) / static_cast<double>(h.count()));
  }
}

std::vector<double> Scaled(std::initializer_list<double> values, double unit) {
  std::vector<double> out;
  for (double v : values) out.push_back(v * unit);
  return out;
}

std::string LoadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string one, five;
  f >> one >> five;
  return one + " " + five;
}

// One blue and one yellow robot (ids 0) on the analytic backend at 60 fps.
Scene OneOnOne() {
  const std::string model = Source("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}";
  return LoadSceneFromString("name: serve_1v1\nbackend: analytic\nframe_rate: 60\nduration: 60\nseed: 1\nrobots:\n"
                             "  - {name: blue0, team: blue, id: 0, model: " + model +
                                 ", start: {x: -1, y: 0}, " + hold + "}\n"
                             "  - {name: yellow0, team: yellow, id: 0, model: " + model +
                                 ", start: {x: 1, y: 0, theta_deg: 180}, " + hold + "}\n",
                             "serve_1v1.yaml", Source("scenes"));
}

// The synchronous interface: one client on TCP sends `frames` requests of one frame's
// step each with a RobotControl for blue's robots (each on a circle) and reads each
// response. Returns the field's summary.
ServeSummary SyncThroughput(const Scene& scene, long long frames) {
  ServeOptions options;
  options.control_port = options.blue_port = options.yellow_port = 0;
  options.sync_port = 0;
  options.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, "analytic"), options);
  ServeSummary summary;
  std::thread server([&] { summary = field.Run([] { return false; }); });
  SimulationSyncRequest request;
  request.set_sim_step(static_cast<float>(1 / scene.frame_rate));
  for (int id : TeamIds(scene, "blue")) {
    RobotCommand* c = request.mutable_robot_control()->add_robot_commands();
    c->set_id(static_cast<unsigned>(id));
    MoveLocalVelocity* m = c->mutable_move_command()->mutable_local_velocity();
    m->set_forward(0.4f);
    m->set_left(0.0f);
    m->set_angular(1.0f);
  }
  const std::string bytes = request.SerializeAsString();
  TcpConnection client = TcpConnect("127.0.0.1", field.sync_port());
  for (long long k = 0; k < frames; ++k) {
    if (!client.WriteMessage(bytes)) break;
    std::optional<std::string> response;
    while (!response) {
      if (!WaitReadableFd(client.fd(), 1) || !client.ReadAvailable()) break;
      response = client.NextMessage(1 << 22);
    }
    if (!response) break;
  }
  server.join();
  return summary;
}

// kB of resident memory (VmRSS in /proc/self/status), 0 where unknown.
long long ResidentKb() {
  std::ifstream f("/proc/self/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
  return 0;
}

// Part 4: a long lockstep match of serve_11v11 on analytic, its memory every simulated minute.
int MemoryOverAMatch(double minutes, bool keep_all) {
  const Scene match = LoadScene(Source("scenes/serve_11v11.yaml"));
  const auto frames = static_cast<long long>(minutes * 60 * match.frame_rate + 0.5);
  const std::string folder = std::filesystem::temp_directory_path().string() + "/serve_bench_logs";
  std::printf("4. Memory over a match: %s (%zu robots, ball) in lockstep on analytic at %g fps, %g simulated minutes;"
              " %s\n", match.name.c_str(), match.robots.size(), match.frame_rate, minutes,
              keep_all ? "every frame kept in memory (--keep-all)" : "logs streamed to disk, plots' history thinned");
  std::printf("  %8s %10s %10s %12s\n", "minute", "frames", "wall, s", "VmRSS, MB");
  ServeOptions options;
  options.lockstep = true;
  options.teams = {"blue", "yellow"};
  options.keep_frames = keep_all ? 0 : 2048;  // twinsim serve's (kPlotFrames)
  std::unique_ptr<RunLogStream> logs;
  const auto per_minute = static_cast<long long>(60 * match.frame_rate + 0.5);
  long long done = 0;
  const Clock::time_point start = Clock::now();
  // From the frame sink: every frame, as it ends; a row at each simulated minute.
  auto report = [&] {
    if (done % per_minute != 0) return;
    std::printf("  %8lld %10lld %10.1f %12.1f\n", done / per_minute, done,
                std::chrono::duration<double>(Clock::now() - start).count(), static_cast<double>(ResidentKb()) / 1024);
    std::fflush(stdout);
  };
  report();
  const Served served = Serve(match, "analytic", options, frames, /*resend=*/0.02, [&](LiveField* field) {
    if (!keep_all) logs = std::make_unique<RunLogStream>(folder, field->result().robot_names, true, match.frame_rate,
                                                               /*background=*/true);
    field->SetFrameSink([&](const std::vector<FrameRecord>& r, const BallRecord* b) {
      if (logs) logs->Append(r, b);
      ++done;
      report();
    });
  });
  std::printf("  %lld frames in %.1f s wall (%.1f x real time); logs in %s\n", served.summary.counters.frames,
              served.summary.wall, served.summary.simulated / served.summary.wall, keep_all ? "-" : folder.c_str());
  return 0;
}

int Main(int argc, char** argv) {
  double seconds = 20;
  long long lockstep_frames = 20000;
  double memory_minutes = 0;
  bool keep_all = false;
  std::optional<CameraSetup> cameras;  // part 1: several cameras (columns, rows)
  bool stream = false;                // part 1: logs streamed as twinsim serve does, memory reported
  ServeOptions realtime;  // part 1's serving thread: twinsim serve's --realtime-priority, --cpu
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc) {
      seconds = std::atof(argv[++i]);
    } else if (a == "--lockstep-frames" && i + 1 < argc) {
      lockstep_frames = std::atoll(argv[++i]);
    } else if (a == "--realtime-priority" && i + 1 < argc) {
      realtime.realtime_priority = std::atoi(argv[++i]);
    } else if (a == "--cpu" && i + 1 < argc) {
      realtime.cpu = std::atoi(argv[++i]);
    } else if (a == "--memory-minutes" && i + 1 < argc) {
      memory_minutes = std::atof(argv[++i]);
    } else if (a == "--stream") {
      stream = true;
    } else if (a == "--keep-all") {
      keep_all = true;
    } else if (a == "--cameras" && i + 2 < argc) {
      cameras.emplace().grid = CameraGrid{std::atoi(argv[i + 1]), std::atoi(argv[i + 2]), 0.4, 4};
      i += 2;
    } else {
      std::fprintf(stderr, "usage: serve_bench [--seconds S] [--lockstep-frames N] [--realtime-priority P] [--cpu C]\n"
                           "                   [--cameras COLUMNS ROWS] [--stream]\n"
                           "       serve_bench --memory-minutes M [--keep-all]\n");
      return 2;
    }
  }
  if (!(seconds > 0) || lockstep_frames <= 0) {
    std::fprintf(stderr, "serve_bench: --seconds and --lockstep-frames must be positive\n");
    return 2;
  }
  std::printf("twinsim serve on the loopback (bench/serve_bench.cc): %u cores, load average %s\n\n",
              std::thread::hardware_concurrency(), LoadAverage().c_str());
  if (memory_minutes > 0) return MemoryOverAMatch(memory_minutes, keep_all);

  // 1 and 2: real time, 11 v 11 and the ball on ODE.
  Scene match = LoadScene(Source("scenes/serve_11v11.yaml"));
  match.cameras = cameras;
  const auto frames = static_cast<long long>(seconds * match.frame_rate + 0.5);
  // --stream: as twinsim serve, the logs streamed to a temporary folder and the plots'
  // history thinned; the resident memory every simulated ten minutes.
  std::unique_ptr<RunLogStream> logs;
  const std::string folder = std::filesystem::temp_directory_path().string() + "/serve_bench_realtime_logs";
  long long done = 0;
  const auto per_ten_minutes = static_cast<long long>(600 * match.frame_rate + 0.5);
  if (stream) realtime.keep_frames = 2048;
  const Served rt = Serve(match, "ode", realtime, frames, /*resend=*/0, [&](LiveField* field) {
    if (!stream) return;
    logs = std::make_unique<RunLogStream>(folder, field->result().robot_names, true, match.frame_rate, /*background=*/true);
    field->SetFrameSink([&](const std::vector<FrameRecord>& r, const BallRecord* b) {
      logs->Append(r, b);
      if (++done % per_ten_minutes == 0 || done == 3600) {
        std::printf("  (streaming) %lld frames, VmRSS %.1f MB\n", done, static_cast<double>(ResidentKb()) / 1024);
        std::fflush(stdout);
      }
    });
  });
  const ServeSummary& s = rt.summary;
  std::printf("1. Real time: %s (%zu robots, %s) on ode at %g fps, %lld frames (%g s); serving thread SCHED_FIFO %d, "
              "CPU %d (0, -1: the normal scheduler, any CPU)\n",
              match.name.c_str(), match.robots.size(), match.ball ? "ball" : "no ball", match.frame_rate, frames, seconds,
              realtime.realtime_priority, realtime.cpu);
  std::printf("  frames run %lld in %.3f s wall (%.4f x real time); late frames %lld; cameras %d (vision packets %lld)\n",
              s.counters.frames, s.wall, s.simulated / s.wall, s.counters.late_frames,
              cameras ? cameras->grid.columns * cameras->grid.rows : 1, s.counters.vision_packets);
  std::printf("  robot controls read %lld (sent: blue %lld, yellow %lld), answered %lld + %lld, refused %lld, "
              "dropped/bad %lld\n",
              s.counters.robot_controls, rt.sent[0], rt.sent[1], rt.answers[0], rt.answers[1], s.counters.refused,
              s.counters.malformed + s.counters.oversized + s.counters.rate_dropped);
  const double period = 1 / match.frame_rate;
  PrintHistogram("frame work (vision; commands, physics, log)", s.timing.frame_work,
                 Scaled({0, 0.5, 1, 1.5, 2, 2.5, 3, 4, 6, 8, 12, 1e3 * period}, 1e-3), 1e-3, "ms");
  std::printf("  slowest frame: %s\n", s.timing.slowest.Brief().c_str());
  std::printf("  latest start: %s\n", s.timing.latest_start.Brief().c_str());
  PrintHistogram("frame start lateness", s.timing.start_lateness,
                 Scaled({0, 0.1, 0.2, 0.5, 1, 1.5, 2, 3, 5, 10, 1e3 * period}, 1e-3), 1e-3, "ms");
  std::printf("\n2. Latency, a RobotControl's arrival (kernel stamp) to its moves stored for the delay line\n");
  std::printf("  p50 %s, p99 %s, max %s (%lld commands; %lld without a kernel stamp)\n",
              FormatDuration(s.timing.command_latency.Quantile(0.5)).c_str(),
              FormatDuration(s.timing.command_latency.Quantile(0.99)).c_str(),
              FormatDuration(s.timing.command_latency.max()).c_str(), s.timing.command_latency.count(),
              s.timing.unstamped);
  const std::vector<double> latency_bins = Scaled({0, 10, 20, 30, 50, 75, 100, 150, 200, 300, 500, 1000, 2000}, 1e-6);
  PrintHistogram("command latency", s.timing.command_latency, latency_bins, 1e-6, "µs");
  PrintHistogram("of which after the loop read it (parse, check, store)", s.timing.command_handling, latency_bins,
                 1e-6, "µs");

  // 3: lockstep throughput, two robots on analytic; then four (serve_2v2).
  std::printf("\n3. Lockstep throughput on analytic, a client thread per team (the default --max-rate)\n");
  std::printf("  %-40s %8s %9s %10s %12s %8s %12s\n", "scene", "frames", "wall, s", "frames/s", "x real time", "resent",
              "latency p99");
  ServeOptions lockstep;
  lockstep.lockstep = true;
  lockstep.teams = {"blue", "yellow"};
  // The default --max-rate (1000 datagrams a second of wall time or of simulated time)
  // does not cap lockstep.
  const Scene one_on_one = OneOnOne();
  const Scene two_on_two = LoadScene(Source("scenes/serve_2v2.yaml"));
  struct Row {
    const Scene* scene;
    const char* label;
    ServeOptions options;
    long long frames;
  };
  const std::vector<Row> rows{
      {&one_on_one, "1 v 1 (two robots)", lockstep, lockstep_frames},
      {&two_on_two, "serve_2v2 (four robots)", lockstep, lockstep_frames},
  };
  for (const Row& row : rows) {
    const Served ls = Serve(*row.scene, "analytic", row.options, row.frames, /*resend=*/0.02);
    const ServeSummary& l = ls.summary;
    std::printf("  %-40s %8lld %9.3f %10.0f %12.1f %8lld %12s\n", row.label, l.counters.frames, l.wall,
                static_cast<double>(l.counters.frames) / l.wall, l.simulated / l.wall, ls.resent[0] + ls.resent[1],
                FormatDuration(l.timing.command_latency.Quantile(0.99)).c_str());
    if (l.counters.rate_dropped > 0) std::printf("    (%lld datagrams over the rate limit)\n", l.counters.rate_dropped);
  }
  // The synchronous interface (TCP), one client stepping a frame per request.
  for (const Row& row : rows) {
    const ServeSummary l = SyncThroughput(*row.scene, row.frames);
    std::printf("  %-40s %8lld %9.3f %10.0f %12.1f %8s %12s\n",
                (std::string(row.label) + ", synchronous").c_str(), l.counters.frames, l.wall,
                static_cast<double>(l.counters.frames) / l.wall, l.simulated / l.wall, "-", "-");
  }
  return 0;
}

}  // namespace
}  // namespace twinsim

int main(int argc, char** argv) {
  try {
    return twinsim::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "serve_bench: %s\n", e.what());
    return 1;
  }
}
