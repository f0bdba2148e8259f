// `twinsim ilc SCENE.yaml --out DIR [--backend B] [--trials N] [--quiet]`: iterative
// learning control of an arm scene (docs/ilc.md): measure the closed-loop process
// sensitivity at several postures, build a learning filter per joint (fitted to it, or
// the controller's model), and run the task trial after trial, learning a feedforward
// between trials.
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/commands/commands.h"
#include "control/closed_loop_frf.h"
#include "control/ilc_report.h"
#include "control/iterative_learning.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/csv_table.h"
#include "io/output_files.h"
#include "render/renderer.h"
#include "scene/arm_scene.h"
#include "scene/ilc_scene.h"

namespace twinsim {
namespace {

struct IlcCommandOptions {
  std::string scene;
  std::string out;       // empty: out/<scene name>_ilc
  std::string backend;   // empty: the scene's
  std::string predictor; // the learned backend's
  int trials = -1;       // -1: the scene's
  bool quiet = false;
};

std::string Num(double v) { return FormatCsvNumber(v); }

// Prints the measured frequency responses' range and each joint's learning filter and convergence.
void PrintIlcFilters(const ArmScene& scene, const IlcSceneRun& run) {
  const ClosedLoopFrf& frf = run.frf;
  const IlcOptions& o = run.options;
  std::string q = "none";
  if (o.q_order > 0) {
    q = "order " + std::to_string(o.q_order) +
        (o.q_cutoffs.empty() ? " at " + Num(o.q_cutoff) + " Hz" : ", cutoff per joint by the convergence criterion") +
        " (zero phase)";
  }
  std::printf("ilc %s: %d postures, PS measured %g..%g Hz in %.2f s; learning filter %s, %s update, gain %g, Q %s\n",
              scene.name.c_str(), static_cast<int>(run.postures.size()), frf.frequency[0],
              frf.frequency[frf.frequency.size() - 1], run.frf_seconds, scene.ilc.learning_filter.c_str(),
              o.update == "norm_optimal" ? "norm-optimal" : "standard", o.gain, q.c_str());
  for (int j = 0; j < scene.plant.dof(); ++j) {
    const double limit = LearningLimitFrequency(frf, j, run.filters[j], o.gain);
    std::printf("  joint %d: %s; |1 - gain PS L| < 1 up to %s; %s, worst |Q|^2 |1 - gain PS S| %.3g\n", j + 1,
                run.filters[j].Summary().c_str(), std::isfinite(limit) ? (Num(limit) + " Hz").c_str() : "every line",
                o.q_order > 0 ? ("Q at " + Num(o.Cutoff(j)) + " Hz").c_str() : "no Q",
                ConvergenceFactor(frf, j, run.filters[j], o).maxCoeff());
  }
}

// Prints one trial's RMS and largest tracking error per joint.
void PrintIlcTrial(int trial, const TrackingTrial& t) {
  std::printf("  trial %2d: RMS error [mrad]", trial);
  for (Eigen::Index j = 0; j < t.error_rms.size(); ++j) std::printf(" %9.4g", 1e3 * t.error_rms[j]);
  std::printf("   max [mrad]");
  for (Eigen::Index j = 0; j < t.error_max.size(); ++j) std::printf(" %9.4g", 1e3 * t.error_max[j]);
  std::printf("\n");
  std::fflush(stdout);
}

// Writes the report (its tables, plots and report.html) into `files`.
void WriteIlcReport(const ArmScene& scene, const IlcSceneRun& run, const std::string& scene_path, OutputFiles* files) {
  if (!RenderingCompiled()) {
    std::fprintf(stderr, "%s: warning: plots and report not drawn: %s\n", scene_path.c_str(), kRenderingNotCompiled);
  }
  const std::unique_ptr<Renderer> renderer = RenderingCompiled() ? MakeDefaultRenderer() : nullptr;
  IlcReportSetup setup;
  setup.name = scene.name;
  setup.backend = run.backend;
  setup.hat = scene.hat.name;
  setup.tracking = run.tracking;
  setup.frf = scene.ilc.frf;
  setup.learning_filter = scene.ilc.learning_filter;
  setup.options = run.options;
  setup.tool = scene.task.writing.tool;
  for (const auto& [file, bytes] :
       MakeIlcReport(setup, scene.plant, run.reference.t, run.frf, run.filters, run.result, renderer.get())) {
    files->Write(file, bytes);
  }
}

int RunIlcCommand(const IlcCommandOptions& options) {
  const ArmScene scene = LoadArmScene(options.scene);
  const std::string out = options.out.empty() ? "out/" + scene.name + "_ilc" : options.out;

  Progress frf_progress("ilc " + scene.name + ": frequency responses", !options.quiet);
  IlcSceneCallbacks callbacks;
  callbacks.frf_progress = [&](int done, int total) {
    frf_progress.Update(done, total, std::to_string(done) + "/" + std::to_string(total) + " joint-postures");
  };
  callbacks.filters_ready = [&](const IlcSceneRun& run) {
    frf_progress.Finish();
    if (!options.quiet) PrintIlcFilters(scene, run);
  };
  callbacks.trial_done = [&](int trial, const TrackingTrial& t) {
    if (!options.quiet) PrintIlcTrial(trial, t);
  };
  const IlcSceneRun run = RunIlcScene(scene, options.backend, options.trials, callbacks, options.predictor);
  const IlcResult& result = run.result;

  // The report: the tables, the plots and report.html.
  OutputFiles files(out);
  WriteIlcReport(scene, run, options.scene, &files);

  const int last = static_cast<int>(result.error_rms.size()) - 1;
  if (!options.quiet) {
    std::printf("%s\n%s\n", result.BriefReport().c_str(), IlcSafeguardSummary(result, run.options).c_str());
    files.PrintWrote();
  }
  if (result.Diverged()) {
    std::fprintf(stderr,
                 "%s: ILC diverged: the worst joint's RMS error grew from %g rad (trial 0) to %g rad (trial %d); "
                 "lower the gain or the robustness filter's cut-off (q_cutoff)\n",
                 options.scene.c_str(), result.WorstRms(0), result.WorstRms(last), last);
    return kExitCheckFailed;
  }
  return kExitOk;
}

}  // namespace

void AddIlcCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<IlcCommandOptions>();
  CLI::App* cmd = app.add_subcommand("ilc", "Iterative learning control of an arm scene's task.");
  cmd->footer(
      "Measures the closed-loop process sensitivity PS (feedforward torque to joint position,\n"
      "feedback closed) per joint at several postures with multisines, builds a learning\n"
      "filter L ~ PS^-1 per joint (fitted to the measurement, or the controller's model) and a\n"
      "zero-phase Butterworth robustness filter Q, then runs the scene's task trial after trial\n"
      "from the same initial state, learning f_{k+1} = Q(f_k + gain L e_k) between trials\n"
      "(the scene's `ilc:` block, docs/ilc.md). Trial 0 runs without learning.\n"
      "Writes DIR/trials.csv (trial,rms1..rmsn,max1..maxn: tracking error per joint, rad or m),\n"
      "DIR/frf.csv, DIR/filters.csv, DIR/feedforward.csv (the last trial's), best_feedforward.csv,\n"
      "safeguard.csv (what the watch over the trials did), errors.csv (trial 0's and the last\n"
      "trial's tracking error, sample by sample), the plots (convergence.png,\n"
      "error.png, bode_joint<j>.png, path.png) and DIR/report.html (self-contained).\n"
      "Exit 1 when the learning diverged (the last trial's worst RMS error is above trial 0's).");
  cmd->add_option("scene", options->scene, "Arm scene file (YAML, docs/scenes.md)")->required();
  cmd->add_option("--out", options->out, "Output folder (default: out/<scene name>_ilc)");
  cmd->add_option("--backend", options->backend,
                  "Backend: analytic, ode, bullet or learned (default: the scene's)");
  cmd->add_option("--predictor", options->predictor,
                  "With --backend learned: an arm predictor for the scene's model (twinsim train)");
  cmd->add_option("--trials", options->trials, "Learning trials after trial 0 (default: the scene's, else 10)")
      ->check(CLI::Range(0, 1000));
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] {
    if (SceneRobotKind(options->scene) != RobotKind::kArm) {
      throw InputError(SourceLocation{options->scene}, "twinsim ilc needs an arm scene (robot: arm)");
    }
    *exit_code = RunIlcCommand(*options);
  });
}

}  // namespace twinsim
