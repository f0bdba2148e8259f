// `twinsim compare --model MODEL --log LOG.csv --out DIR [--backend B ...] [--predictor P]`
#include <cstdio>
#include <memory>

#include "analysis/omni_compare.h"
#include "app/commands/commands.h"
#include "app/progress.h"
#include "backends/omni_backend.h"
#include "backends/omni_engine.h"
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/omni_log.h"
#include "io/yaml_reader.h"
#include "learning/omni_predictor.h"

namespace twinsim {
namespace {

struct CompareCliOptions {
  std::string model;
  std::string log;
  std::string out;
  std::vector<std::string> backends;  // empty: every physics backend built, and learned with --predictor
  std::string predictor;
  bool quiet = false;
};

int Compare(const CompareCliOptions& options) {
  // Check everything before running or writing anything.
  const YAML::Node root = LoadYamlFile(options.model);
  const std::string kind = root["robot"] && root["robot"].IsScalar() ? root["robot"].Scalar() : "omni";
  if (kind != "omni")
    throw InputError(SourceLocation{options.model, root["robot"].Mark().line + 1},
                     "compare of '" + kind + "' models is not available in this build (known: omni)");
  const OmniModel model = LoadOmniModel(options.model);
  const OmniLog log = ReadOmniLog(options.log);
  const double frame_rate = 1.0 / log.frame_period;

  std::shared_ptr<const OmniPredictor> predictor;
  if (!options.predictor.empty()) {
    predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(options.predictor));
    predictor->CheckUse(model, frame_rate, 1, "compare of " + options.log);
  }

  std::vector<std::string> backends = options.backends;
  if (backends.empty()) {
    backends = AvailableOmniEngines();
    if (predictor) backends.push_back("learned");
  }
  OmniCompareOptions compare;
  compare.horizons = DefaultCompareHorizons(frame_rate);
  for (const std::string& b : backends) compare.sources.push_back({b, b, BackendOptions{predictor}});

  Progress progress("compare", !options.quiet);
  const OmniCompareResult result = CompareOmniLog(
      model, log, compare, [&](long done, long total, const std::string& what) { progress.Update(done, total, what); });
  progress.Finish();

  const std::string errors_path = options.out + "/errors.csv";
  const std::string paths_path = options.out + "/paths.csv";
  WriteFileAtomically(errors_path, FormatCompareErrorsCsv(result));
  WriteFileAtomically(paths_path, FormatComparePathsCsv(log, result));

  if (!options.quiet) {
    std::printf("compared %zu rows of %s (%g fps) through %s, delay %d frames\n\n%s\n", log.rows.size(),
                options.log.c_str(), frame_rate, model.name.c_str(),
                model.command_delay_frames + model.vision_delay_frames, result.Report().c_str());
    std::printf("wrote:\n  %s\n  %s\n", errors_path.c_str(), paths_path.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddCompareCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<CompareCliOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare how well backends predict a measured log.");
  cmd->footer(
      "Every backend replays the log (as 'twinsim replay' does) at four horizons: row i is predicted\n"
      "from the measured state K frames earlier and the logged commands since, with the model's delay.\n"
      "  1 frame    K = 1\n"
      "  4 frames   K = 4\n"
      "  1 s        K = round(frame rate)\n"
      "  free run   one run from the first row on the commands alone (K = 0)\n"
      "Rows predicted: those with enough history (delay + 15 warm-up frames + K); errors are over them.\n"
      "Outputs in DIR:\n"
      "  errors.csv  source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse\n"
      "              (m, m, rad; one row per backend and horizon)\n"
      "  paths.csv   t,measured_x,measured_y,measured_theta,<backend>_x,<backend>_y,<backend>_theta,...\n"
      "              (the free run of every backend, one row per log row)\n"
      "Default backends: every physics backend built, plus learned when --predictor is given.");
  cmd->add_option("--model", options->model, "Model file (YAML)")->required();
  cmd->add_option("--log", options->log, "Measured log (CSV: t,x,y,theta,vx_cmd,vy_cmd,omega_cmd)")->required();
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->add_option("--backend", options->backends,
                  "Backend to compare (repeat --backend): ode, bullet, analytic or learned");
  cmd->add_option("--predictor", options->predictor, "1-frame predictor for the learned backend (from twinsim train)");
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Compare(*options); });
}

}  // namespace twinsim
