// `twinsim serve SCENE.yaml [--lockstep] [--tournament] [--out DIR] ...`
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include "app/commands/commands.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "io/output_files.h"
#include "learning/omni_predictor.h"
#include "scene/run_log_stream.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "serve/live_field.h"

namespace twinsim {
namespace {

// Frames of the match the plots draw at least (a long match thinned evenly to fewer
// than twice as many; LiveField's keep_frames).
constexpr int kPlotFrames = 2048;

struct ServeCommandOptions {
  std::string scene;
  std::string backend;    // empty: the scene's
  std::string predictor;  // for --backend learned
  std::string out;        // empty: out/<scene name>
  long long seed = -1;    // -1: the scene's
  std::string teams;      // "blue,yellow"
  std::string driving_noise = "model";  // on | off | model (commands.h)
  bool quiet = false;
  ServeOptions serve;
};

// What serve prints when it starts: the scene, the robots, the ports and the options
// that change how it serves.
void PrintServing(const Scene& scene, const std::string& backend, const std::string& out,
                  const ServeCommandOptions& options, const LiveField& field) {
  std::printf("serving %s: %zu robot(s) on %s at %g fps, %s\n", scene.name.c_str(), scene.robots.size(),
              field.result().backend.c_str(), scene.frame_rate,
              field.sync_port() >= 0 ? "synchronous" : options.serve.lockstep ? "lockstep" : "real time");
  const std::vector<std::string> backends = RobotBackends(scene, backend);
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    const SceneRobot& r = scene.robots[i];
    const std::string predictor =
        r.predictor ? " (" + std::filesystem::path(r.predictor_path).filename().string() + ")" : "";
    std::printf("  %s %d: %s on %s%s\n", r.team.c_str(), r.id, r.name.c_str(), backends[i].c_str(), predictor.c_str());
  }
  std::printf("control %s:%d%s, blue %s:%d, yellow %s:%d; vision to %s:%d.\n",
              options.serve.listen.c_str(), field.control_port(), options.serve.tournament ? " (refused: tournament)" : "",
              options.serve.listen.c_str(), field.blue_port(), options.serve.listen.c_str(), field.yellow_port(),
              options.serve.vision_address.c_str(), options.serve.vision_port);
  std::printf("logs to %s/ as the match runs; Ctrl-C stops and draws the plots.\n", out.c_str());
  if (!field.cameras().empty()) {
    const double unseen = UnseenShare(field.cameras(), scene.field);
    std::printf("%zu cameras, capture %s", field.cameras().size(),
                scene.cameras->staggered ? "staggered (each camera its own clock)" : "synchronous");
    if (unseen > 0) std::printf("; %.1f %% of the field inside the walls is seen by none", 100 * unseen);
    std::printf("\n");
  }
  if (IsMulticast(ParseIpv4(options.serve.vision_address)))
    std::printf("vision is multicast (ttl %d, interface %s)\n", options.serve.vision_ttl,
                options.serve.vision_interface.empty() ? "by route" : options.serve.vision_interface.c_str());
  if (field.sync_port() >= 0)
    std::printf("synchronous interface on %s:%d (TCP; %s's RobotControl); the UDP ports are not served\n",
                options.serve.listen.c_str(), field.sync_port(), options.serve.sync_team.c_str());
  if (field.grsim_port() >= 0)
    std::printf("grSim's protocol on %s:%d%s\n", options.serve.listen.c_str(), field.grsim_port(),
                options.serve.tournament ? " (replacement refused: tournament)" : "");
  if (field.receive_buffer() < field.receive_buffer_asked())
    std::printf("receive buffers: %d bytes per port of %d asked; a burst of commands may be dropped by the kernel\n"
                "  (counted; raise net.core.rmem_max, or serve with CAP_NET_ADMIN)\n",
                field.receive_buffer(), field.receive_buffer_asked());
  if (options.serve.realtime_priority > 0 || options.serve.cpu >= 0)
    std::printf("serving thread: SCHED_FIFO %d, CPU %s\n", options.serve.realtime_priority,
                options.serve.cpu >= 0 ? std::to_string(options.serve.cpu).c_str() : "any");
  std::fflush(stdout);
}

int Serve(ServeCommandOptions& options) {
  Scene scene = LoadScene(options.scene);
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  scene.driving_noise = options.driving_noise;
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  const std::string out = options.out.empty() ? "out/" + scene.name : options.out;
  if (!options.teams.empty()) {
    std::stringstream list(options.teams);
    for (std::string team; std::getline(list, team, ',');) options.serve.teams.push_back(team);
  }

  OmniBackendOptions backend_options;
  if (!options.predictor.empty())
    backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(options.predictor));
  // The logs go to disk frame by frame (a crash keeps every finished frame) and the
  // field keeps a thinned history for the plots: memory stays flat for any length.
  options.serve.keep_frames = kPlotFrames;
  LiveField field(scene, MakeSimulation(scene, backend, backend_options), options.serve);
  // Written by a thread of the stream's own: a slow write never makes a frame late.
  RunLogStream logs(out, field.result().robot_names, field.simulation().has_ball(), scene.frame_rate,
                    /*background=*/true);
  field.SetFrameSink([&logs](const std::vector<FrameRecord>& records, const BallRecord* ball) {
    logs.Append(records, ball);
  });

  if (!options.quiet) PrintServing(scene, backend, out, options, field);
  Progress progress("serve " + scene.name, !options.quiet);
  // Ctrl-C (or SIGTERM) is how a served field ends: the frames run so far are written.
  const ServeSummary summary = field.Run([] { return InterruptSignal() != 0; },
                                         [&](const ServeSummary& s) { progress.Status(s.Brief()); });
  progress.Finish();
  ClearInterrupt();
  logs.Finish();  // every frame that ran on disk (or the file a write failed on named)

  OutputFiles files(out);
  // commands.csv, what every robot sent, exactly: `twinsim run SCENE --commands
  // commands.csv` replays it.
  for (const std::string& name : logs.names()) files.Add(name);
  if (summary.counters.frames > 0) WriteOmniRunPlots(scene, field.result(), &files);
  if (!options.quiet) {
    std::printf("%s\n%s", summary.Brief().c_str(), summary.Report().c_str());
    if (summary.counters.frames == 0) std::printf("no frame ran: nothing written\n");
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddServeCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<ServeCommandOptions>();
  CLI::App* cmd = app.add_subcommand("serve", "Serve a scene's field live over the league's network protocol.");
  cmd->footer(
      "Teams drive their robots with the SSL simulation protocol (RobotControl on the blue and\n"
      "yellow ports, SimulatorCommand on the control port) and receive SSL-Vision packets of what\n"
      "the observer sees, through the scene's delay loop and camera noise (docs/serve.md).\n"
      "Robots are blue or yellow with ids by the scene's `team:` and `id:` (docs/scenes.md), each on\n"
      "its own `backend:` or the field's (the scene's, or --backend); robots on different backends\n"
      "do not touch (docs/backends.md). The scene is the squad: a robot with `present: false` starts\n"
      "off the field and a teleport with present: true adds it (present: false removes one;\n"
      "by_force moves by force).\n"
      "Real time by default; --lockstep steps frame k when every connected team has sent its\n"
      "command for it. DIR/trajectory.csv (and _NAME per further robot) and DIR/truth.csv as\n"
      "`twinsim run` writes them, DIR/ball.csv when the scene has a `ball:` (kicks, chips, the\n"
      "dribbler and ball teleports then work; docs/ball.md) and DIR/commands.csv are written as\n"
      "the match runs (after a crash they hold every finished frame); Ctrl-C stops and draws the plots.");
  cmd->add_option("scene", options->scene, "Scene file (YAML, see docs/scenes.md)")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet, analytic or learned (default: the scene's; robots with their own "
                  "`backend:` keep theirs)");
  cmd->add_option("--predictor", options->predictor, "1-step predictor for --backend learned (from twinsim train)");
  cmd->add_option("--out", options->out, "Output folder for the logs (default: out/<scene name>)");
  cmd->add_option("--seed", options->seed, "Random seed (default: the scene's)")->check(NonNegativeNumber());
  cmd->add_option("--listen", options->serve.listen, "Address the ports listen on (default 127.0.0.1)");
  cmd->add_option("--control-port", options->serve.control_port, "Simulator control port (default 10300; 0: any free)");
  cmd->add_option("--blue-port", options->serve.blue_port, "Blue team's robot control port (default 10301)");
  cmd->add_option("--yellow-port", options->serve.yellow_port, "Yellow team's robot control port (default 10302)");
  cmd->add_option("--grsim-port", options->serve.grsim_port,
                  "Also take grSim's own protocol (grSim_Packet: commands and replacement) on this port\n"
                  "(grSim's is 20011; default: off; docs/serve.md)");
  cmd->add_option("--grsim-blue-status-port", options->serve.grsim_blue_status_port,
                  "With --grsim-port: where blue's robot status (grSim's Robots_Status) goes, at the address\n"
                  "its grSim packets come from")
      ->capture_default_str();
  cmd->add_option("--grsim-yellow-status-port", options->serve.grsim_yellow_status_port,
                  "With --grsim-port: the same for yellow")
      ->capture_default_str();
  cmd->add_option("--sync-port", options->serve.sync_port,
                  "Serve the protocol's synchronous interface on this TCP port instead (each\n"
                  "SimulationSyncRequest steps the field; length-delimited messages; docs/serve.md)");
  cmd->add_option("--sync-team", options->serve.sync_team,
                  "Synchronous interface: the team its RobotControl commands (blue or yellow; default blue)");
  cmd->add_option("--vision-address", options->serve.vision_address,
                  "Address the vision packets go to: unicast (default 127.0.0.1), or a multicast group\n"
                  "such as the league's 224.5.23.2");
  cmd->add_option("--vision-port", options->serve.vision_port, "Port the vision packets go to (default 10020)");
  cmd->add_option("--vision-ttl", options->serve.vision_ttl, "Multicast vision: hops (default 1: this network only)");
  cmd->add_option("--vision-interface", options->serve.vision_interface,
                  "Multicast vision: leave by the interface with this address (default: the route's)");
  cmd->add_option("--realtime-priority", options->serve.realtime_priority,
                  "Real time: serve at this SCHED_FIFO priority, 1..99 (needs root or CAP_SYS_NICE; default 0: normal)");
  cmd->add_option("--cpu", options->serve.cpu, "Real time: pin the serving thread to this CPU (default: any)");
  cmd->add_flag("--lockstep", options->serve.lockstep, "Step a frame when every connected team has sent its command");
  cmd->add_option("--teams", options->teams, "Lockstep: teams to wait for from frame 0 (blue, yellow or blue,yellow)");
  cmd->add_flag("--tournament", options->serve.tournament,
                "Refuse simulator control; one client address per team port");
  cmd->add_option("--max-datagram", options->serve.max_datagram, "Largest datagram read, bytes (default 8192)");
  cmd->add_option("--receive-buffer", options->serve.receive_buffer,
                  "Receive buffer per port, bytes (default: a quarter second at --max-rate; beyond\n"
                  "net.core.rmem_max only with CAP_NET_ADMIN)")
      ->check(NonNegativeNumber());
  cmd->add_option("--max-rate", options->serve.max_rate, "Datagrams per second per port before dropping (lockstep: also per simulated second; default 1000)");
  cmd->add_option("--geometry-period", options->serve.geometry_period, "Seconds between geometry packets (default 1)");
  cmd->add_option("--boundary", options->serve.boundary, "Metres between the walls and the field lines (default 0.3)");
  cmd->add_option("--frames", options->serve.max_frames, "Stop after this many frames (default: at Ctrl-C)")
      ->check(NonNegativeNumber());
  AddDrivingNoiseOption(cmd, &options->driving_noise);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Serve(*options); });
}

}  // namespace twinsim
