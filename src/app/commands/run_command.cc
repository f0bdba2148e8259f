// `twinsim run SCENE.yaml [--backend B] [--out DIR] [--seed N]`
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands/commands.h"
#include "app/progress.h"
#include "backends/omni_backend.h"
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/omni_log.h"
#include "learning/omni_predictor.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace twinsim {
namespace {

struct RunOptions {
  std::string scene;
  std::string backend;  // empty: the scene's
  std::string out;      // empty: out/<scene name>
  long long seed = -1;  // -1: the scene's
  std::string predictor;  // for --backend learned
  bool quiet = false;
};

// The observer's log of one robot: only frames whose observation arrived.
std::vector<OmniLogRow> ObserverLog(const std::vector<FrameRecord>& frames) {
  std::vector<OmniLogRow> rows;
  for (const auto& f : frames)
    if (f.observed) rows.push_back(OmniLogRow{f.t, f.seen, f.command});
  return rows;
}

// The ground truth of one robot: true pose and velocity at every frame.
std::string TruthCsv(const std::vector<FrameRecord>& frames) {
  std::string out = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,vx,vy,omega\n";
  for (const auto& f : frames) {
    const double v[] = {f.t, f.truth.x, f.truth.y, f.truth.theta, f.command.vx, f.command.vy, f.command.omega,
                        f.truth_velocity.vx, f.truth_velocity.vy, f.truth_velocity.omega};
    for (int i = 0; i < 10; ++i) {
      if (i) out += ',';
      out += FormatCsvNumber(v[i]);
    }
    out += '\n';
  }
  return out;
}

// The path plot a scene asks for: each robot's true path and/or what its observer saw.
PathPlot MakeScenePathPlot(const PlotSpec& spec, const Scene& scene, const SimulationResult& result,
                           const std::string& backend) {
  PathPlot plot;
  plot.title = PlotTitle(spec, scene.name, backend, scene.seed);
  plot.width = spec.width;
  plot.height = spec.height;
  plot.orientation_every = spec.orientation_every;
  const WorldRect field{-scene.field.length / 2, scene.field.length / 2, -scene.field.width / 2, scene.field.width / 2};
  plot.field = field;
  if (spec.region_is_field) {
    const double m = 0.15;  // m, so that the outline is not on the frame
    plot.region = WorldRect{field.x_min - m, field.x_max + m, field.y_min - m, field.y_max + m};
  } else {
    plot.region = spec.region;
  }
  const bool single = result.frames.size() == 1;
  const std::string source = !spec.source.empty() ? spec.source : single ? "both" : "truth";
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    const std::vector<FrameRecord>& frames = result.frames[i];
    const std::string& robot = result.robot_names[i];
    if (source == "truth" || source == "both") {
      PlotPath p;
      p.name = single ? "truth" : source == "both" ? robot + " truth" : robot;
      for (std::size_t k = 0; k < frames.size(); ++k) {
        p.poses.push_back(frames[k].truth);
        p.frames.push_back(static_cast<int>(k));
      }
      plot.paths.push_back(std::move(p));
    }
    if (source == "seen" || source == "both") {
      PlotPath p;
      const int late = i < scene.robots.size() ? scene.robots[i].model.vision_delay_frames : 0;
      const std::string what = "seen by the observer (" + std::to_string(late) + (late == 1 ? " frame" : " frames") + " late)";
      p.name = single ? what : source == "both" ? robot + " " + what : robot + ", " + what;
      // Numbered by the frame the camera captured them in, so that both paths tick the
      // same moments and the ticks differ only by what the camera got wrong.
      for (std::size_t k = 0; k < frames.size(); ++k) {
        if (!frames[k].observed) continue;
        p.poses.push_back(frames[k].seen);
        p.frames.push_back(static_cast<int>(k) - late);
      }
      plot.paths.push_back(std::move(p));
    }
  }
  return plot;
}

int Run(const RunOptions& options) {
  Scene scene = LoadScene(options.scene);
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  const std::string out = options.out.empty() ? "out/" + scene.name : options.out;

  BackendOptions backend_options;
  if (!options.predictor.empty())
    backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(options.predictor));
  Simulation sim = MakeSimulation(scene, backend, backend_options);
  const int frames = scene.num_frames();
  Progress progress("run " + scene.name, !options.quiet);
  const auto start = std::chrono::steady_clock::now();
  SimulationResult result = sim.Run(frames, [&](int done, int total) {
    progress.Update(done, total, std::to_string(done) + "/" + std::to_string(total) + " frames");
  });
  progress.Finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<std::string> written;
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    const std::string suffix = i == 0 ? "" : "_" + result.robot_names[i];
    const std::string log_path = out + "/trajectory" + suffix + ".csv";
    WriteOmniLog(log_path, ObserverLog(result.frames[i]));
    WriteFileAtomically(out + "/truth" + suffix + ".csv", TruthCsv(result.frames[i]));
    written.push_back(log_path);
    written.push_back(out + "/truth" + suffix + ".csv");
  }

  if (!scene.plots.empty() && !RenderingCompiled()) {
    // The logs are the contract's main output: a build without a renderer still writes them.
    std::fprintf(stderr, "%s: warning: %zu plot(s) not drawn: %s\n", options.scene.c_str(), scene.plots.size(),
                 kRenderingNotCompiled);
  } else if (!scene.plots.empty()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    for (const PlotSpec& spec : scene.plots) {
      const std::string path = out + "/" + spec.file;
      WritePng(path, RenderPathPlot(MakeScenePathPlot(spec, scene, result, backend), *renderer));
      written.push_back(path);
    }
  }

  if (!options.quiet) {
    const double simulated = (frames - 1) / scene.frame_rate;
    std::printf("scene %s: %zu robot(s) on %s, %d frames at %g fps (%.2f s simulated) in %.2f s wall, %.0fx real time\n",
                scene.name.c_str(), result.frames.size(), backend.c_str(), frames, scene.frame_rate, simulated, wall,
                wall > 0 ? simulated / wall : 0.0);
    const FrameRecord& last = result.frames[0].back();
    std::printf("  %s ends at x = %.3f m, y = %.3f m, theta = %.1f deg\n", result.robot_names[0].c_str(), last.truth.x,
                last.truth.y, last.truth.theta * 180 / kPi);
    std::printf("wrote:\n");
    for (const auto& w : written) std::printf("  %s\n", w.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddRunCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run a scene headless and write what the observer saw.");
  cmd->footer(
      "Writes DIR/trajectory.csv (t,x,y,theta,vx_cmd,vy_cmd,omega_cmd: the first robot as its\n"
      "observer saw it, four frames late by default, lost frames left out), DIR/truth.csv (the\n"
      "true pose and velocity every frame), and the same with _NAME for every further robot;\n"
      "and the PNG plots the scene's `plots:` list asks for (docs/rendering.md).");
  cmd->add_option("scene", options->scene, "Scene file (YAML, see docs/scenes.md)")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet, analytic or learned (default: the scene's)");
  cmd->add_option("--predictor", options->predictor, "1-frame predictor for --backend learned (from twinsim train)");
  cmd->add_option("--out", options->out, "Output folder (default: out/<scene name>)");
  cmd->add_option("--seed", options->seed, "Random seed (default: the scene's)")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Run(*options); });
}

}  // namespace twinsim
