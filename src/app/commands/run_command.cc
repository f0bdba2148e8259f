// `twinsim run SCENE.yaml [--backend B] [--out DIR] [--seed N]`
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands/commands.h"
#include "app/progress.h"
#include "backends/arm/arm_backend.h"
#include "backends/learned/learned_arm_backend.h"
#include "backends/omni_backend.h"
#include "control/computed_torque.h"
#include "control/tracking_plots.h"
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/omni_log.h"
#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "scene/arm_scene.h"
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

// The backend an arm scene's plant runs on: every arm backend is built here, so that
// one place decides what `--backend` (and, for a learned backend, `--predictor`) means
// for arms. `learned` steps the arm with a predictor (twinsim train) trained for the
// scene's model: it replaces the plant's bodies, friction and effects. Throws InputError
// for an unknown or uncompiled backend, a missing, unreadable or mismatched predictor,
// and a predictor given to another backend.
std::unique_ptr<ArmBackend> MakeArmSceneBackend(const ArmScene& scene, const std::string& backend,
                                                const RunOptions& options) {
  if (backend == "learned") {
    if (options.predictor.empty()) {
      throw InputError(SourceLocation{options.scene},
                       "--backend learned needs --predictor P (an arm predictor from 'twinsim train')");
    }
    const ArmPredictor predictor = ArmPredictor::Load(options.predictor);
    return MakeLearnedArmBackend(scene.plant, predictor);
  }
  if (!options.predictor.empty())
    throw InputError("--predictor applies to --backend learned only; arm scene '" + scene.name + "' runs on " + backend);
  return MakeArmBackend(backend, scene.plant);
}

// What only the simulation knows, per sample and joint: the tracking error, the demand
// before clamping, the controller's model-based part, the drive torque applied and the
// torque the plant needed (TrackingTrial's columns).
std::string ArmTrackingCsv(const TrackingTrial& trial) {
  const Eigen::MatrixXd error = trial.q_ref - trial.q;
  return JointColumnsCsv(trial.t, {"error", "demand", "model", "applied", "needed"},
                         {&error, &trial.demand, &trial.model_torque, &trial.applied, &trial.needed});
}

std::string ArmPlotTitle(const ArmPlotSpec& spec, const ArmScene& scene, const std::string& backend,
                         const std::string& what) {
  PlotSpec generic;
  generic.title = spec.title.empty() ? "{scene} ({backend}): " + what : spec.title;
  return PlotTitle(generic, scene.name, backend, scene.seed);
}

int RunArm(const RunOptions& options) {
  ArmScene scene = LoadArmScene(options.scene);
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  const std::string out = options.out.empty() ? "out/" + scene.name : options.out;
  const ArmReference reference = ArmSceneReference(scene);
  std::unique_ptr<ArmBackend> engine = MakeArmSceneBackend(scene, backend, options);

  const auto start = std::chrono::steady_clock::now();
  TrackingOptions tracking = scene.tracking;
  tracking.backend = backend;
  tracking.dither_seed = scene.seed;
  const TrackingTrial trial = RunTrackingTrial(scene.plant, std::move(engine), scene.hat, reference, tracking);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<std::string> written;
  WriteFileAtomically(out + "/trajectory.csv", ArmSceneTrajectoryCsv(scene, trial));
  written.push_back(out + "/trajectory.csv");
  WriteFileAtomically(out + "/tracking.csv", ArmTrackingCsv(trial));
  written.push_back(out + "/tracking.csv");

  if (!scene.plots.empty() && !RenderingCompiled()) {
    std::fprintf(stderr, "%s: warning: %zu plot(s) not drawn: %s\n", options.scene.c_str(), scene.plots.size(),
                 kRenderingNotCompiled);
  } else if (!scene.plots.empty()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    for (const ArmPlotSpec& spec : scene.plots) {
      if (spec.type == "tool_path") {
        PathPlot plot = ToolPathPlot(trial, scene.plant, scene.task.writing.tool,
                                     ArmPlotTitle(spec, scene, backend, "tool point path"));
        plot.width = spec.width, plot.height = spec.height;
        WritePng(out + "/" + spec.file, RenderPathPlot(plot, *renderer));
        written.push_back(out + "/" + spec.file);
      } else if (spec.type == "joint_torques") {
        const std::string stem = spec.file.substr(0, spec.file.size() - 4);
        for (int j = 0; j < scene.plant.dof(); ++j) {
          SeriesPlot plot = JointTorquePlot(
              trial, scene.plant, j,
              ArmPlotTitle(spec, scene, backend, "joint " + std::to_string(j + 1) + " torque"));
          plot.width = spec.width, plot.height = spec.height;
          const std::string path = out + "/" + stem + "_joint" + std::to_string(j + 1) + ".png";
          WritePng(path, RenderSeriesPlot(plot, *renderer));
          written.push_back(path);
        }
      } else {
        SeriesPlot plot = TrackingErrorPlot(trial, scene.plant, ArmPlotTitle(spec, scene, backend, "tracking error"));
        plot.width = spec.width, plot.height = spec.height;
        WritePng(out + "/" + spec.file, RenderSeriesPlot(plot, *renderer));
        written.push_back(out + "/" + spec.file);
      }
    }
  }

  if (!options.quiet) {
    const double simulated = trial.t.size() > 0 ? trial.t[trial.t.size() - 1] : 0.0;
    std::printf("scene %s: arm %s with %s (model %s) on %s, %lld samples at %g s (%.2f s simulated) in %.2f s wall\n",
                scene.name.c_str(), scene.plant.name.c_str(), trial.controller.c_str(), scene.hat.name.c_str(),
                backend.c_str(), static_cast<long long>(trial.t.size()), trial.sample_time, simulated, wall);
    std::printf("joint  max error [mrad]  RMS error [mrad]  saturated [%%]  command RMS [N m]\n");
    for (Eigen::Index j = 0; j < trial.error_max.size(); ++j) {
      std::printf("%5lld  %16.4g  %16.4g  %13.2f  %17.4g\n", static_cast<long long>(j + 1), 1e3 * trial.error_max[j],
                  1e3 * trial.error_rms[j], 100 * trial.saturated_fraction[j], trial.command_rms[j]);
    }
    std::printf("wrote:\n");
    for (const auto& w : written) std::printf("  %s\n", w.c_str());
  }
  return kExitOk;
}

int Run(const RunOptions& options) {
  if (SceneRobotKind(options.scene) == "arm") return RunArm(options);
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
      "and the PNG plots the scene's `plots:` list asks for (docs/rendering.md).\n"
      "Arm scenes (`robot: arm`, docs/scenes.md) run a tracking controller along a task (the\n"
      "writing task of seed 001, a hold, a step, a sinusoid, or seeded random motion to learn\n"
      "from) and write DIR/trajectory.csv (t,q1..qn,tau1..taun,qd1..qdn,qref1..qrefn: the arm\n"
      "log, tau the commands sent), DIR/tracking.csv (error, demand, model torque, applied and\n"
      "needed torque per joint) and the plots asked for (tool_path, joint_torques,\n"
      "tracking_error). --seed picks the random task's motion and the controller's dither.\n"
      "--backend learned --predictor P runs an arm scene on a predictor trained for its model.");
  cmd->add_option("scene", options->scene, "Scene file (YAML, see docs/scenes.md)")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet, analytic or learned (default: the scene's)");
  cmd->add_option("--predictor", options->predictor, "1-step predictor for --backend learned (from twinsim train)");
  cmd->add_option("--out", options->out, "Output folder (default: out/<scene name>)");
  cmd->add_option("--seed", options->seed, "Random seed (default: the scene's)")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Run(*options); });
}

}  // namespace twinsim
