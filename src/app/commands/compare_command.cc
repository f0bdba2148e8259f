// `twinsim compare --model MODEL --log LOG.csv --out DIR [--backend B ...] [--predictor P ...]`
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "analysis/omni_compare.h"
#include "app/commands/commands.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "core/progress.h"
#include "engines/omni_engine.h"
#include "io/output_files.h"
#include "io/yaml_reader.h"
#include "learning/omni_predictor.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/omni/omni_log.h"

namespace twinsim {
namespace {

// Seed 000 Fig. 4: the measured path and every model's free run from the same start
// under the same commands, over the first `seconds` of the log.
PathPlot FreeRunPlot(const OmniLog& log, const OmniCompareResult& result, const std::string& model, double seconds) {
  PathPlot plot;
  plot.title = "The first " + std::to_string(static_cast<int>(seconds)) + " s of " + log.path +
               ": measured and simulated (" + model + ")";
  const double t_end = log.rows.front().t + seconds;
  PlotPath measured{"measured", {}, {}};
  for (std::size_t i = 0; i < log.rows.size() && log.rows[i].t <= t_end; ++i) {
    measured.poses.push_back(log.rows[i].pose);
    measured.frames.push_back(log.FrameIndex(i));
  }
  plot.paths.push_back(std::move(measured));
  for (const ComparePath& run : result.free_runs) {
    PlotPath path{run.source, {}, {}};
    for (std::size_t i = 0; i < run.t.size() && run.t[i] <= t_end; ++i) {
      path.poses.push_back(run.pose[i]);
      path.frames.push_back(log.FrameIndex(i));
    }
    plot.paths.push_back(std::move(path));
  }
  return plot;
}

// Position error against the prediction horizon, one line per source.
SeriesPlot ErrorPlot(const OmniCompareResult& result, double frame_rate) {
  SeriesPlot plot;
  plot.title = "Prediction error against horizon";
  plot.x_label = "horizon [s]";
  plot.y_label = "position RMSE [mm]";
  plot.height = 700;
  for (const CompareErrorRow& row : result.rows) {
    if (row.horizon_frames == 0) continue;  // the free run has no fixed horizon
    auto it = std::find_if(plot.series.begin(), plot.series.end(), [&](const PlotSeries& s) { return s.name == row.source; });
    if (it == plot.series.end()) {
      plot.series.push_back(PlotSeries{row.source, {}, {}});
      it = plot.series.end() - 1;
    }
    it->x.push_back(row.horizon_frames / frame_rate);
    it->y.push_back(row.position_rmse * 1000);
  }
  // The models' errors fill most of the height, with room for every baseline's start; a
  // baseline far above them (constant velocity 3 s ahead is metres) leaves the top,
  // drawn as far as it stays inside.
  double x_max = 0, y_models = 0, y_all = 0;
  std::map<std::string, double> baseline_low;  // each baseline's smallest error
  for (const CompareErrorRow& row : result.rows) {
    if (row.horizon_frames == 0) continue;
    const double mm = row.position_rmse * 1000;
    x_max = std::max(x_max, row.horizon_frames / frame_rate);
    y_all = std::max(y_all, mm);
    if (row.backend != "baseline") {
      y_models = std::max(y_models, mm);
    } else {
      auto [it, added] = baseline_low.emplace(row.source, mm);
      if (!added) it->second = std::min(it->second, mm);
    }
  }
  double top = 1.5 * y_models;
  for (const auto& [name, low] : baseline_low) top = std::max(top, 1.2 * low);
  if (y_models > 0 && y_all > top) {
    plot.range = WorldRect{0, x_max, 0, top};
    plot.title += " (baselines beyond the top are cut)";
  }
  return plot;
}

struct CompareCliOptions {
  std::string model;
  std::string log;
  std::string out;
  std::vector<std::string> backends;  // empty: every physics backend built, and learned with --predictor
  std::vector<std::string> predictors;
  double plot_seconds = 8;  // s of the log drawn in paths.png
  bool quiet = false;
  OmniLogSelector select;  // omni logs holding several robots
};

int Compare(const CompareCliOptions& options) {
  // Check everything before running or writing anything.
  const std::string kind = ModelFileRobotKind(options.model);
  if (kind != "omni")
    throw InputError(SourceLocation{options.model},
                     "compare of '" + kind + "' models is not available in this build (known: omni)");
  const OmniModel model = LoadOmniModel(options.model);
  const OmniLog log = ReadOmniLog(options.log, options.select);
  const double frame_rate = 1.0 / log.frame_period;

  std::vector<std::shared_ptr<const OmniPredictor>> predictors;
  for (const std::string& path : options.predictors) predictors.push_back(std::make_shared<OmniPredictor>(OmniPredictor::Load(path)));
  const OmniCompareOptions compare = MakeCompareOptions(model, log, options.backends, predictors, options.predictors);

  Progress progress("compare", !options.quiet);
  const OmniCompareResult result = CompareOmniLog(
      model, log, compare, [&](long done, long total, const std::string& what) { progress.Update(done, total, what); });
  progress.Finish();

  OutputFiles files(options.out);
  files.Write("errors.csv", FormatCompareErrorsCsv(result));
  files.Write("paths.csv", FormatComparePathsCsv(log, result));
  if (RenderingCompiled()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    files.WritePng("paths.png", RenderPathPlot(FreeRunPlot(log, result, model.name, options.plot_seconds), *renderer));
    files.WritePng("errors.png", RenderSeriesPlot(ErrorPlot(result, frame_rate), *renderer));
  } else {
    std::fprintf(stderr, "compare: warning: plots not drawn: %s\n", kRenderingNotCompiled);
  }

  if (!options.quiet) {
    std::printf("compared %zu rows of %s (%g fps) through %s, delay %d frames\n\n%s\n", log.rows.size(),
                options.log.c_str(), frame_rate, model.name.c_str(),
                model.command_delay_frames + model.vision_delay_frames, result.FullReport().c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddCompareCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<CompareCliOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare how well backends predict a measured log.");
  cmd->footer(
      "Every backend replays the log (as 'twinsim replay' does) at six horizons: row i is predicted\n"
      "from the state estimated K frames earlier and the logged commands since, with the model's delay.\n"
      "  1 frame    K = 1\n"
      "  4 frames   K = 4\n"
      "  0.25 s     K = round(frame rate / 4)\n"
      "  1 s        K = round(frame rate)\n"
      "  3 s        K = round(3 x frame rate), predicted from every (K/24)-th frame\n"
      "  free run   one run from the first row on the commands alone (K = 0)\n"
      "Rows predicted: those with enough history (delay + 15 warm-up frames + K); errors are over them.\n"
      "Horizons the log is too short for are left out. Beside the backends, two predictions of no\n"
      "model on the first backend's rows: constant_velocity (the last two measured poses\n"
      "extrapolated) and integrated_command (the commands at the model's delay as the velocity).\n"
      "Outputs in DIR:\n"
      "  errors.csv  source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse\n"
      "              (m, m, rad; one row per backend and horizon; backend 'baseline' for the two above)\n"
      "  paths.csv   t,measured_x,measured_y,measured_theta,<backend>_x,<backend>_y,<backend>_theta,...\n"
      "              (the free run of every backend, one row per log row)\n"
      "Default backends: every physics backend built, plus learned when --predictor is given.\n"
      "Several --predictor files (the seed's and a residual one, say) each run on the learned backend,\n"
      "labelled 'learned' or 'residual' after their kind (and their file's name where two share one).");
  cmd->add_option("--model", options->model, "Model file (YAML)")->required();
  cmd->add_option("--log", options->log, "Measured log (CSV: t,x,y,theta,vx_cmd,vy_cmd,omega_cmd)")->required();
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->add_option("--backend", options->backends,
                  "Backend to compare (repeat --backend): ode, bullet, analytic or learned");
  cmd->add_option("--predictor", options->predictors,
                  "1-frame predictor for the learned backend (from twinsim train; repeat for several)");
  cmd->add_option("--plot-seconds", options->plot_seconds, "Seconds of the log drawn in paths.png")
      ->capture_default_str()
      ->check(PositiveNumber());
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  AddLogSelectorOptions(cmd, &options->select);
  cmd->callback([options, exit_code] { *exit_code = Compare(*options); });
}

}  // namespace twinsim
