// `twinsim batch SWEEP.yaml --out DIR [--jobs N] [--resume]`, also under mpirun.
#include <cstdio>
#include <memory>

#include "app/commands/commands.h"
#include "batch/batch_runner.h"
#include "batch/sweep.h"
#include "core/error.h"

namespace twinsim {
namespace {

struct BatchCliOptions {
  std::string sweep;
  BatchOptions batch;
  bool quiet = false;
};

int Batch(BatchCliOptions options) {
  const Sweep sweep = LoadSweep(options.sweep);
  options.batch.progress = !options.quiet;
  const BatchSummary summary = RunBatch(sweep, options.batch);
  if (summary.writer && !options.quiet) std::printf("sweep %s: %s", sweep.name.c_str(), summary.FullReport().c_str());
  return kExitOk;
}

}  // namespace

void AddBatchCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<BatchCliOptions>();
  CLI::App* cmd = app.add_subcommand("batch", "Run a sweep of jobs on every core, or across machines under mpirun.");
  cmd->footer(
      "A sweep file (docs/batch.md) names the command every job runs (run, replay, compare), fixed\n"
      "parameters, a grid and random draws over scenes, seeds, backends, predictors and any key of\n"
      "the scene or model files (scene.KEY, plant.KEY, model.KEY). Writes DIR/jobs/ID/ per job (the\n"
      "command's files and result.json, written last), DIR/summary.csv (job,seed,<swept>,status,\n"
      "wall_s,<metrics>,error: one row per job) and DIR/summary.html (the metrics against the swept\n"
      "parameters). A failed job is a row with its error; the others go on (exit 0).\n"
      "Outputs are the same for any --jobs and any number of MPI ranks, but for wall times.\n"
      "--resume keeps the complete job folders of an interrupted run and runs the rest.\n"
      "Across machines: mpirun -np R build/twinsim batch SWEEP.yaml --out DIR (a folder all ranks\n"
      "see); rank 0 hands out jobs one at a time and writes the summary.");
  cmd->add_option("sweep", options->sweep, "Sweep file (YAML, see docs/batch.md)")->required();
  cmd->add_option("--out", options->batch.out, "Output folder")->required();
  cmd->add_option("--jobs,-j", options->batch.jobs, "Threads per process (0: one per core; under MPI: cores per rank)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  cmd->add_flag("--resume", options->batch.resume, "Continue an interrupted sweep in DIR");
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Batch(*options); });
}

}  // namespace twinsim
