// `twinsim replay --model MODEL --log LOG.csv --out OUT.csv [--backend B] [--horizon K]`
#include <cstdio>
#include <memory>

#include "analysis/omni_replay.h"
#include "app/commands/commands.h"
#include "app/progress.h"
#include "backends/omni_backend.h"
#include "core/error.h"
#include "io/omni_log.h"
#include "learning/omni_predictor.h"
#include "io/yaml_reader.h"

namespace twinsim {
namespace {

struct ReplayOptions {
  std::string model;
  std::string log;
  std::string out;
  std::string backend = "ode";
  int horizon = 4;
  std::string predictor;
  bool quiet = false;
};

int Replay(const ReplayOptions& options) {
  // Check everything before writing anything.
  const YAML::Node root = LoadYamlFile(options.model);
  const std::string kind = root["robot"] && root["robot"].IsScalar() ? root["robot"].Scalar() : "omni";
  if (kind != "omni")
    throw InputError(SourceLocation{options.model, root["robot"].Mark().line + 1},
                     "replay of '" + kind + "' models is not available in this build (known: omni)");
  const OmniModel model = LoadOmniModel(options.model);
  const OmniLog log = ReadOmniLog(options.log);
  OmniReplayOptions replay;
  replay.backend = options.backend;
  replay.horizon = options.horizon;
  if (!options.predictor.empty())
    replay.backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(options.predictor));

  Progress progress("replay", !options.quiet);
  OmniReplayResult result = ReplayOmniLog(model, log, replay, [&](int done, int total) { progress.Update(done, total); });
  progress.Finish();
  WritePoseCsv(options.out, result.t, result.pose);

  if (!options.quiet) {
    std::printf("replayed %zu rows of %s through %s on %s (K = %d, delay %d frames): %d predicted, position RMSE %.4f m\n",
                log.rows.size(), options.log.c_str(), model.name.c_str(), options.backend.c_str(), options.horizon,
                result.delay_frames, result.num_predicted(), PositionRmse(log, result));
    std::printf("wrote:\n  %s\n", options.out.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddReplayCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Replay a measured log through a model.");
  cmd->footer(
      "Omni robots: row i of OUT.csv (t,x,y,theta) is the model's prediction of frame i from the\n"
      "measured state K frames earlier and the logged commands since, with the model's delay.\n"
      "K = 0: one free run from the first row. Rows without enough history hold the measured pose.");
  cmd->add_option("--model", options->model, "Model file (YAML)")->required();
  cmd->add_option("--log", options->log, "Measured log (CSV: t,x,y,theta,vx_cmd,vy_cmd,omega_cmd)")->required();
  cmd->add_option("--out", options->out, "Output CSV")->required();
  cmd->add_option("--backend", options->backend, "Backend: ode, bullet, analytic or learned")->capture_default_str();
  cmd->add_option("--predictor", options->predictor, "1-frame predictor for --backend learned (from twinsim train)");
  cmd->add_option("--horizon", options->horizon, "K, frames predicted ahead (0: free run)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Replay(*options); });
}

}  // namespace twinsim
