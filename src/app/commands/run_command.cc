// `twinsim run SCENE.yaml [--backend B] [--out DIR] [--seed N]`
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands/commands.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "core/progress.h"
#include "io/output_files.h"
#include "render/renderer.h"
#include "scene/arm_scene.h"
#include "scene/scene.h"
#include "scene/scene_ensemble.h"
#include "scene/scene_run.h"

namespace twinsim {
namespace {

struct RunOptions {
  std::string scene;
  std::string backend;  // empty: the scene's
  std::string out;      // empty: out/<scene name>
  long long seed = -1;  // -1: the scene's
  std::string predictor;  // for --backend learned
  std::string commands;   // a recorded match to replay (commands.csv)
  std::string driving_noise = "model";  // on | off | model: every robot's driving_noise.simulated
  int samples = 0;  // > 0: an ensemble of this many rollouts under the driving noise
  std::string parameter_uncertainty = "on";  // samples 1..: a linear predictor's weights drawn too
  int jobs = 0;     // the ensemble's threads (0: one per core)
  bool quiet = false;
};

void WarnPlotsNotDrawn(const std::string& scene_path, std::size_t plots) {
  if (plots > 0 && !RenderingCompiled())
    std::fprintf(stderr, "%s: warning: %zu plot(s) not drawn: %s\n", scene_path.c_str(), plots, kRenderingNotCompiled);
}

int RunArm(const RunOptions& options) {
  if (!options.commands.empty())
    throw InputError(options.scene + ": --commands replays an omni field's commands; this is an arm scene");
  ArmScene scene = LoadArmScene(options.scene);
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  const std::string out = options.out.empty() ? "out/" + scene.name : options.out;
  const auto start = std::chrono::steady_clock::now();
  const TrackingTrial trial = RunArmScene(scene, backend, options.predictor);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  OutputFiles files(out);
  WriteArmRunFiles(scene, trial, backend, /*plots=*/true, &files);
  WarnPlotsNotDrawn(options.scene, scene.plots.size());

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
    files.PrintWrote();
  }
  return kExitOk;
}

// `run --samples N`: sample 0's files as a plain run writes them, then samples.csv and
// fan.png (scene/scene_ensemble.h).
int RunEnsemble(const Scene& scene, const std::string& backend, const RunOptions& options, const std::string& out) {
  Progress progress("run " + scene.name + " x" + std::to_string(options.samples), !options.quiet);
  const auto start = std::chrono::steady_clock::now();
  OmniEnsembleOptions ensemble_options;
  ensemble_options.samples = options.samples;
  ensemble_options.jobs = options.jobs;
  ensemble_options.parameter_draws = options.parameter_uncertainty == "on";
  const OmniEnsemble ensemble = RunOmniEnsemble(scene, backend, options.predictor, ensemble_options, [&](int done, int total) {
    progress.Update(done, total, std::to_string(done) + "/" + std::to_string(total) + " samples");
  });
  progress.Finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  OutputFiles files(out);
  WriteOmniRunFiles(scene, ensemble.first, /*plots=*/true, &files);
  WarnPlotsNotDrawn(options.scene, scene.plots.size() + 1);
  files.Write("samples.csv", FormatEnsembleCsv(ensemble));
  if (RenderingCompiled()) files.WritePng("fan.png", RenderSeriesPlot(EnsemblePlot(ensemble), *MakeDefaultRenderer()));
  if (!options.quiet) {
    std::printf("scene %s: %d samples of %zu robot(s) on %s under their driving noise, %d frames each, in %.2f s wall\n",
                scene.name.c_str(), options.samples, ensemble.first.frames.size(), ensemble.first.backend.c_str(),
                scene.num_frames(), wall);
    // How far the samples end from each other: the spread of the first robot's last position.
    double mx = 0, my = 0, n = 0;
    for (const auto& path : ensemble.paths)
      if (std::isfinite(path.back().x)) mx += path.back().x, my += path.back().y, ++n;
    if (n > 1) {
      mx /= n, my /= n;
      double s2 = 0;
      for (const auto& path : ensemble.paths)
        if (std::isfinite(path.back().x)) s2 += std::pow(path.back().x - mx, 2) + std::pow(path.back().y - my, 2);
      std::printf("  %s ends around x = %.3f m, y = %.3f m, %.3f m RMS apart from that\n", ensemble.robot.c_str(), mx, my,
                  std::sqrt(s2 / n));
    }
    files.PrintWrote();
  }
  return kExitOk;
}

int Run(const RunOptions& options) {
  if (SceneRobotKind(options.scene) == RobotKind::kArm) {
    if (options.driving_noise != "model") throw InputError("--driving-noise is for omni robots; " + options.scene + " is an arm scene");
    if (options.samples > 0) throw InputError("--samples draws omni robots' driving noise; " + options.scene + " is an arm scene");
    return RunArm(options);
  }
  Scene scene = LoadScene(options.scene);
  scene.driving_noise = options.driving_noise;
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  if (!options.commands.empty()) ReplayCommandLog(options.commands, &scene);
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  const std::string out = options.out.empty() ? "out/" + scene.name : options.out;
  if (options.samples > 0) return RunEnsemble(scene, backend, options, out);
  if (options.jobs != 0) throw InputError("--jobs runs the samples of --samples N in parallel; give --samples too");

  const int frames = scene.num_frames();
  Progress progress("run " + scene.name, !options.quiet);
  const auto start = std::chrono::steady_clock::now();
  SimulationResult result = RunOmniScene(scene, backend, options.predictor, [&](int done, int total) {
    progress.Update(done, total, std::to_string(done) + "/" + std::to_string(total) + " frames");
  });
  progress.Finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  OutputFiles files(out);
  WriteOmniRunFiles(scene, result, /*plots=*/true, &files);
  // The logs are the contract's main output: a build without a renderer still writes them.
  WarnPlotsNotDrawn(options.scene, scene.plots.size());
  if (const std::string grip = DescribeGrip(result.grip); !grip.empty())
    std::fprintf(stderr, "%s: warning: %s\n", options.scene.c_str(), grip.c_str());

  if (!options.quiet) {
    const double simulated = (frames - 1) / scene.frame_rate;
    std::printf("scene %s: %zu robot(s) on %s, %d frames at %g fps (%.2f s simulated) in %.2f s wall, %.0fx real time\n",
                scene.name.c_str(), result.frames.size(), result.backend.c_str(), frames, scene.frame_rate, simulated, wall,
                wall > 0 ? simulated / wall : 0.0);
    const FrameRecord& last = result.frames[0].back();
    if (last.present) {
      std::printf("  %s ends at x = %.3f m, y = %.3f m, theta = %.1f deg\n", result.robot_names[0].c_str(),
                  last.truth.x, last.truth.y, last.truth.theta * 180 / kPi);
    } else {
      std::printf("  %s ends off the field (present: false)\n", result.robot_names[0].c_str());
    }
    files.PrintWrote();
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
      "true pose and velocity every frame the robot is on the field: a scene robot with\n"
      "`present: false` has none), and the same with _NAME for every further robot;\n"
      "DIR/ball.csv (t,x,y,z,vx,vy,vz) when the scene has a `ball:` (docs/ball.md); and the PNG\n"
      "plots the scene's `plots:` list asks for (docs/rendering.md).\n"
      "A scene's robots may each name their own backend (`backend:`, `predictor:`; docs/scenes.md):\n"
      "--backend and --predictor then set the field's, for the robots that name none.\n"
      "Arm scenes (`robot: arm`, docs/scenes.md) run a tracking controller along a task (the\n"
      "writing task of seed 001, a hold, a step, a sinusoid, or seeded random motion to learn\n"
      "from) and write DIR/trajectory.csv (t,q1..qn,tau1..taun,qd1..qdn,qref1..qrefn: the arm\n"
      "log, tau the commands sent), DIR/tracking.csv (error, demand, model torque, applied and\n"
      "needed torque per joint) and the plots asked for (tool_path, joint_torques,\n"
      "tracking_error). --seed picks the random task's motion and the controller's dither.\n"
      "--backend learned --predictor P runs an arm scene on a predictor trained for its model.");
  cmd->add_option("scene", options->scene, "Scene file (YAML, see docs/scenes.md)")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet, analytic or learned (default: the scene's; robots with their own "
                  "`backend:` keep theirs)");
  cmd->add_option("--predictor", options->predictor, "1-step predictor for --backend learned (from twinsim train)");
  cmd->add_option("--out", options->out, "Output folder (default: out/<scene name>)");
  cmd->add_option("--seed", options->seed, "Random seed (default: the scene's)")->check(NonNegativeNumber());
  cmd->add_option("--commands", options->commands,
                  "Replay a recorded match: every robot sends its rows of this file (commands.csv of\n"
                  "twinsim serve; docs/serve.md), for as many frames as it holds");
  AddDrivingNoiseOption(cmd, &options->driving_noise);
  AddParameterUncertaintyOption(cmd, &options->parameter_uncertainty, true);
  cmd->add_option("--samples", options->samples,
                  "Omni: N rollouts that differ in the robots' driving noise (and a learned robot's drawn predictor,\n"
                  "--parameter-uncertainty): sample 0's files as a plain run,\n"
                  "samples.csv (t,sample,x,y,theta: the first robot's true pose) and fan.png; at most 10000")
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--jobs", options->jobs, "Threads for --samples (0: one per core); the files do not depend on it")
      ->check(NonNegativeNumber());
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Run(*options); });
}

}  // namespace twinsim
