// `twinsim tune-pid SCENE.yaml --out DIR [--backend B] [--iterations N] [--start model|zeros]
//                  [--threads N] [--seed N] [--baselines]`
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

#include "app/commands/commands.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/csv_table.h"
#include "io/output_files.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "tuning/pid_baselines.h"
#include "tuning/pid_tuning.h"
#include "tuning/tuned_pid_yaml.h"

namespace twinsim {
namespace {

struct TunePidCliOptions {
  std::string scene;
  std::string out;
  std::string backend;   // empty: the scene's
  int iterations = -1;   // -1: the scene's tune_pid block
  std::string start;     // empty: the scene's tune_pid block
  int threads = 0;
  long long seed = -1;
  bool baselines = false;
  bool quiet = false;
};

std::string ScoreCsvFields(const TestRunScore& s) {
  std::string out;
  for (double v : {s.quality, s.distance, s.deviation, s.rotation, s.stop_distance, s.avg_speed, s.end_deviation_pct}) {
    out += ',';
    out += FormatCsvNumber(v);
  }
  return out;
}

constexpr const char* kScoreColumns = "quality,distance,deviation,rotation,stop_distance,avg_speed,end_deviation_pct";

// The plots of the learning, into *files.
void WritePlots(const TestRunEvaluator& evaluator, const PidTuningResult& r, OutputFiles* files) {
  if (!RenderingCompiled()) return;
  std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
  const std::string& name = evaluator.scene().name;

  // Seed Fig. 1: the quality of every tested set, and of the current set.
  SeriesPlot quality;
  quality.title = "PID learning on " + evaluator.backend() + " (" + name + "): quality of every test run";
  quality.x_label = "iteration";
  quality.y_label = "quality [m]";
  PlotSeries tested{"tested sets", {}, {}, true}, current{"current set", {}, {}};
  for (const auto& it : r.iterations) {
    for (const auto& s : it.tested) tested.x.push_back(it.iteration), tested.y.push_back(s.quality);
    current.x.push_back(it.iteration), current.y.push_back(it.score.quality);
  }
  quality.series = {tested, current};
  files->WritePng("quality.png", RenderSeriesPlot(quality, *renderer));

  // Seed Fig. 2: the four components of the current set's quality.
  SeriesPlot parts;
  parts.title = "The current set's test run: the four parts of its quality";
  parts.x_label = "iteration";
  parts.y_label = "m or rad";
  PlotSeries d{"distance [m]", {}, {}}, dev{"deviation [m]", {}, {}}, rot{"rotation [rad]", {}, {}},
      stop{"stop distance [m]", {}, {}};
  for (const auto& it : r.iterations) {
    for (PlotSeries* s : {&d, &dev, &rot, &stop}) s->x.push_back(it.iteration);
    d.y.push_back(it.score.distance), dev.y.push_back(it.score.deviation);
    rot.y.push_back(it.score.rotation), stop.y.push_back(it.score.stop_distance);
  }
  parts.series = {d, dev, rot, stop};
  files->WritePng("components.png", RenderSeriesPlot(parts, *renderer));

  // Seed Fig. 3: the parameters over the iterations, each relative to its scale.
  const Eigen::VectorXd scale = DefaultPidScale();
  const std::vector<std::string> names = PidParameterNames();
  for (int axis = 0; axis < 3; ++axis) {
    SeriesPlot params;
    const std::string axis_name = names[6 * axis].substr(0, names[6 * axis].find('.'));
    params.title = "The " + axis_name + " controller's parameters (relative to the hand-tuned size)";
    params.x_label = "iteration";
    params.y_label = "parameter / scale";
    for (int k = 0; k < 6; ++k) {
      PlotSeries s{names[6 * axis + k].substr(axis_name.size() + 1), {}, {}};
      for (const auto& it : r.iterations) {
        s.x.push_back(it.iteration);
        s.y.push_back(it.parameters[6 * axis + k] / scale[6 * axis + k]);
      }
      params.series.push_back(s);
    }
    files->WritePng("parameters_" + axis_name + ".png", RenderSeriesPlot(params, *renderer));
  }

  // The test run before and after, as the camera saw it.
  PathPlot path;
  path.title = "Test run on " + evaluator.backend() + ": the start set and the learned set";
  for (const auto& [label, p] : {std::pair<std::string, const Eigen::VectorXd*>{"start set", &r.start_parameters},
                                 {"learned set", &r.best_parameters}}) {
    PlotPath pp;
    pp.name = label;
    for (const FrameRecord& f : evaluator.Frames(*p)) pp.poses.push_back(f.truth);
    path.paths.push_back(pp);
  }
  files->WritePng("path.png", RenderPathPlot(path, *renderer));
}

int TunePidCommand(const TunePidCliOptions& options) {
  Scene scene = LoadScene(options.scene);
  if (options.seed >= 0) scene.seed = static_cast<std::uint64_t>(options.seed);
  PidTuningOptions tuning = ReadPidTuningOptions(scene);
  if (options.iterations > 0) tuning.iterations = options.iterations;
  if (!options.start.empty()) tuning.start = options.start;
  tuning.threads = options.threads;
  std::string why;
  if (!tuning.IsValid(&why)) throw InputError(SourceLocation{options.scene}, "tune_pid: " + why);
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  // A learned robot's predictor stands for the robot with its controller: it has no
  // PID parameters to tune (on the field's backend or a robot's own).
  const std::vector<std::string> backends = RobotBackends(scene, backend);
  if (std::find(backends.begin(), backends.end(), "learned") != backends.end())
    throw InputError(backend == "learned" && !options.backend.empty() ? SourceLocation{} : SourceLocation{options.scene},
                     "tune-pid tunes the on-board controller, which the physics engines simulate and a learned "
                     "predictor does not: use --backend ode, bullet or analytic, and no robot's own 'backend: "
                     "learned'");
  const TestRunEvaluator evaluator(scene, backend, tuning.weights);

  Progress progress("tune-pid " + scene.name, !options.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  const PidTuningResult r = TunePid(evaluator, tuning, [&](const PidTuningIteration& it) {
    char detail[128];
    std::snprintf(detail, sizeof detail, "iteration %d: quality %.3f, %.2f m/s", it.iteration, it.score.quality,
                  it.score.avg_speed);
    progress.Update(it.iteration + 1, tuning.iterations, detail);
  });
  progress.Finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  OutputFiles files(options.out);
  // learning.csv (the contract): one row per iteration for the current set.
  std::string learning = std::string("iteration,") + kScoreColumns + "\n";
  std::string sets = std::string("iteration,set,") + kScoreColumns + "\n";
  std::string params = "iteration";
  for (const auto& n : PidParameterNames()) params += "," + n;
  params += "\n";
  for (const auto& it : r.iterations) {
    learning += std::to_string(it.iteration) + ScoreCsvFields(it.score) + "\n";
    sets += std::to_string(it.iteration) + ",0" + ScoreCsvFields(it.score) + "\n";
    for (std::size_t k = 0; k < it.tested.size(); ++k)
      sets += std::to_string(it.iteration) + "," + std::to_string(k + 1) + ScoreCsvFields(it.tested[k]) + "\n";
    params += std::to_string(it.iteration);
    for (int k = 0; k < kPidParameters; ++k) params += "," + FormatCsvNumber(it.parameters[k]);
    params += "\n";
  }
  files.Write("pid.yaml", FormatTunedPidYaml(evaluator, r, options.out));
  files.Write("learning.csv", learning);
  files.Write("sets.csv", sets);
  files.Write("parameters.csv", params);
  WritePlots(evaluator, r, &files);

  std::string baselines_table;
  if (options.baselines) {
    const std::vector<BaselineResult> b = RunPidBaselines(evaluator, r, tuning, options.quiet);
    std::string csv = std::string("method,test_runs,") + kScoreColumns + "\n";
    for (const auto& x : b) csv += x.method + "," + std::to_string(x.test_runs) + ScoreCsvFields(x.score) + "\n";
    files.Write("baselines.csv", csv);
    char line[256];
    for (const auto& x : b) {
      std::snprintf(line, sizeof line, "  %-22s %5d runs  quality %7.3f  %.2f m/s  end deviation %5.1f %%",
                    x.method.c_str(), x.test_runs, x.score.quality, x.score.avg_speed, x.score.end_deviation_pct);
      baselines_table += line + (x.detail.empty() ? "" : "  (" + x.detail + ")") + "\n";
    }
  }

  if (!options.quiet) {
    const TestRunScore& s0 = r.iterations.front().score;
    std::printf("tune-pid %s on %s: %zu iterations, %d test runs in %.2f s (%s)\n", scene.name.c_str(),
                backend.c_str(), r.iterations.size(), r.test_runs, wall, r.search.termination.c_str());
    std::printf("  start set:   quality %7.3f, %.2f m/s, end deviation %.1f %%\n", s0.quality, s0.avg_speed,
                s0.end_deviation_pct);
    std::printf("  learned set: quality %7.3f, %.2f m/s, end deviation %.1f %% (iteration %d)\n", r.best_score.quality,
                r.best_score.avg_speed, r.best_score.end_deviation_pct, r.search.best_iteration);
    if (!baselines_table.empty()) std::printf("baselines at the same number of test runs:\n%s", baselines_table.c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddTunePidCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<TunePidCliOptions>();
  CLI::App* cmd = app.add_subcommand("tune-pid", "Learn the robot's 18 on-board PID parameters by policy gradient.");
  cmd->footer(
      "The scene is a test run (one robot, commands of type test_drive; docs/pid_tuning.md) with an\n"
      "optional tune_pid: block. Each iteration perturbs every parameter by -eps, 0 or +eps in n sets,\n"
      "drives them all (in parallel; the result does not depend on --threads) and steps each parameter\n"
      "by eta where the averages say so (seed 000, equations 3 to 6).\n"
      "Writes DIR/pid.yaml (the robot's model with the learned controller; it extends the scene's\n"
      "model file), DIR/learning.csv (iteration,quality,distance,deviation,rotation,stop_distance,\n"
      "avg_speed,end_deviation_pct for the current set), DIR/sets.csv (every test run),\n"
      "DIR/parameters.csv, and the plots quality.png, components.png, parameters_*.png, path.png.\n"
      "--baselines adds Ziegler-Nichols and a general optimiser (NLopt Subplex) at the same\n"
      "number of test runs, in DIR/baselines.csv.");
  cmd->add_option("scene", options->scene, "Test-run scene (YAML)")->required();
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet or analytic (default: the scene's)");
  cmd->add_option("--iterations", options->iterations, "Iterations (default: the scene's tune_pid block, else 10)")
      ->check(PositiveNumber());
  cmd->add_option("--start", options->start, "Start from the model's controller or from all zeros")
      ->check(CLI::IsMember({"model", "zeros"}));
  cmd->add_option("--threads", options->threads, "Worker threads (default 0: one per core)")
      ->check(NonNegativeNumber());
  cmd->add_option("--seed", options->seed, "Random seed (default: the scene's)")->check(NonNegativeNumber());
  cmd->add_flag("--baselines", options->baselines, "Also tune by Ziegler-Nichols and by NLopt's Subplex");
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = TunePidCommand(*options); });
}

}  // namespace twinsim
