// `twinsim compare --model MODEL [--model ...] --log LOG.csv --out DIR [--backend B ...] [--predictor P ...]`
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "analysis/arm_compare.h"
#include "analysis/omni_calibration_report.h"
#include "analysis/omni_compare.h"
#include "analysis/learned_noise.h"
#include "app/commands/commands.h"
#include "backends/omni_backend_factory.h"
#include "core/engine_names.h"
#include "core/error.h"
#include "core/progress.h"
#include "engines/omni_engine.h"
#include "identification_omni/omni_identification.h"
#include "io/csv_table.h"
#include "io/output_files.h"
#include "io/printf_number.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"
#include "render/image_stack.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
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

// The models' errors fill most of the height, with room for every baseline's start; a
// baseline far above them (constant velocity 3 s ahead is metres) leaves the top,
// drawn as far as it stays inside. `baselines` names the baselines' series.
void CutBaselinesAboveModels(SeriesPlot* plot, const std::set<std::string>& baselines) {
  double x_max = 0, y_models = 0, y_all = 0;
  std::map<std::string, double> baseline_low;  // each baseline's smallest error
  for (const PlotSeries& series : plot->series) {
    for (std::size_t i = 0; i < series.y.size(); ++i) {
      x_max = std::max(x_max, series.x[i]);
      y_all = std::max(y_all, series.y[i]);
      if (!baselines.count(series.name)) {
        y_models = std::max(y_models, series.y[i]);
      } else {
        auto [it, added] = baseline_low.emplace(series.name, series.y[i]);
        if (!added) it->second = std::min(it->second, series.y[i]);
      }
    }
  }
  double top = 1.5 * y_models;
  for (const auto& [name, low] : baseline_low) top = std::max(top, 1.2 * low);
  if (y_models > 0 && y_all > top) {
    plot->range = WorldRect{0, x_max, 0, top};
    plot->title += " (baselines beyond the top are cut)";
  }
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
  std::set<std::string> baselines;
  for (const CompareErrorRow& row : result.rows)
    if (row.backend == "baseline") baselines.insert(row.source);
  CutBaselinesAboveModels(&plot, baselines);
  return plot;
}

struct CompareCliOptions {
  std::vector<std::string> models;  // omni: one; arm: one or more, side by side
  std::string log;
  std::string out;
  std::vector<std::string> backends;  // empty: every physics backend built, and learned with --predictor
  std::vector<std::string> predictors;
  double plot_seconds = 8;  // s of the log drawn in paths.png
  std::vector<double> horizons;  // arm: s, the simulation windows (0: the free run); empty: the default
  std::string parameter_uncertainty = "on";  // omni: the calibration with the parameters' covariance too
  bool quiet = false;
  OmniLogSelector select;  // omni logs holding several robots
};

// Arm sources: every model on every backend asked for (default analytic), and the learned
// backend once per predictor (over the first model). Labelled by backend, or by model
// file and backend when several models are compared.
std::vector<ArmCompareSource> ArmSources(const CompareCliOptions& options) {
  std::vector<std::pair<std::string, ArmModel>> models;
  std::set<std::string> stems;
  for (const std::string& path : options.models) {
    const std::string stem = std::filesystem::path(path).stem().string();
    models.emplace_back(stems.insert(stem).second ? stem : path, LoadArmModel(path));
  }
  std::vector<std::string> backends = options.backends;
  if (backends.empty()) backends.push_back("analytic");
  const bool learned = std::count(backends.begin(), backends.end(), "learned") > 0;
  if (learned && options.predictors.empty())
    throw InputError("--backend learned needs --predictor (an arm predictor from twinsim train)");
  if (!options.predictors.empty() && !learned) backends.push_back("learned");
  const std::vector<std::string> known = AvailableArmBackends();
  std::vector<ArmCompareSource> sources;
  for (const std::string& backend : backends) {
    if (std::find(known.begin(), known.end(), backend) == known.end())
      throw InputError("--backend: unknown arm backend '" + backend + "' in this build");
    if (backend == "learned") continue;
    for (const auto& [label, model] : models)
      sources.push_back({models.size() > 1 ? label + "/" + backend : backend, model, backend, {}});
  }
  for (const std::string& path : options.predictors) {
    ArmCompareSource s{"learned", models.front().second, "learned", {}};
    if (options.predictors.size() > 1) s.name += "/" + std::filesystem::path(path).stem().string();
    s.backend_options.predictor = std::make_shared<ArmPredictor>(ArmPredictor::Load(path));
    sources.push_back(std::move(s));
  }
  return sources;
}

// Per joint, the measured q and every source's free run over the first `seconds` of the
// log, stacked; runs that leave the measured range by more than its span are cut there.
RgbaImage ArmFreeRunImage(const ArmLog& log, const ArmModel& model, const ArmCompareResult& result, double seconds,
                          Renderer& renderer) {
  const double t_end = log.t[0] + seconds;
  RgbaImage image;
  for (int j = 0; j < log.dof; ++j) {
    SeriesPlot plot;
    plot.height = 360;
    const bool prismatic = model.joints.at(static_cast<std::size_t>(j)).type == JointType::kPrismatic;
    plot.y_label = "q" + std::to_string(j + 1) + (prismatic ? " [m]" : " [rad]");
    plot.title = "joint " + std::to_string(j + 1) + ": measured, and a free run from the logged torques";
    PlotSeries measured{"measured", {}, {}};
    double low = HUGE_VAL, high = -HUGE_VAL;
    for (int i = 0; i < log.rows() && log.t[i] <= t_end; ++i) {
      measured.x.push_back(log.t[i]);
      measured.y.push_back(log.q(i, j));
      low = std::min(low, log.q(i, j));
      high = std::max(high, log.q(i, j));
    }
    plot.series.push_back(std::move(measured));
    double simulated_low = low, simulated_high = high;
    for (const auto& [name, score] : result.scores) {
      if (score.free_run_start < 0) continue;
      PlotSeries run{name, {}, {}};
      for (Eigen::Index r = 0; r < score.free_run.rows(); ++r) {
        const int i = score.free_run_start + 1 + static_cast<int>(r);
        if (log.t[i] > t_end) break;
        run.x.push_back(log.t[i]);
        run.y.push_back(score.free_run(r, j));
        simulated_low = std::min(simulated_low, run.y.back());
        simulated_high = std::max(simulated_high, run.y.back());
      }
      plot.series.push_back(std::move(run));
    }
    const double span = std::max(high - low, 1e-6);
    if (simulated_low < low - span || simulated_high > high + span) {
      plot.range = WorldRect{log.t[0], std::min(t_end, log.t[log.rows() - 1]), low - span, high + span};
      plot.title += " (cut)";
    }
    RgbaImage panel = RenderSeriesPlot(plot, renderer);
    image = j == 0 ? std::move(panel) : StackImages(image, panel);
  }
  return image;
}

// Every source's and baseline's position RMSE against the horizon, RMS over the joints
// (the windowed horizons; the free run has none).
SeriesPlot ArmErrorPlot(const ArmCompareResult& result) {
  SeriesPlot plot;
  plot.title = "Simulated from the logged torques: error against horizon (RMS over joints)";
  plot.x_label = "horizon [s]";
  plot.y_label = "position RMSE [mrad or mm]";
  auto rms = [](const Eigen::VectorXd& v) { return 1000 * std::sqrt(v.squaredNorm() / std::max<Eigen::Index>(1, v.size())); };
  PlotSeries hold{"hold (no model)", {}, {}}, velocity{"constant velocity (no model)", {}, {}};
  for (const auto& [name, score] : result.scores) {
    PlotSeries series{name, {}, {}};
    for (const ArmHorizonScore& h : score.horizons) {
      if (h.horizon == 0) continue;
      series.x.push_back(h.horizon);
      series.y.push_back(rms(h.rmse));
      if (&score == &result.scores.front().second) {
        hold.x.push_back(h.horizon);
        hold.y.push_back(rms(h.hold));
        velocity.x.push_back(h.horizon);
        velocity.y.push_back(rms(h.constant_velocity));
      }
    }
    plot.series.push_back(std::move(series));
  }
  plot.series.push_back(std::move(hold));
  plot.series.push_back(std::move(velocity));
  CutBaselinesAboveModels(&plot, {plot.series[plot.series.size() - 2].name, plot.series.back().name});
  return plot;
}

int CompareArm(const CompareCliOptions& options) {
  // Check everything before running or writing anything.
  const std::vector<ArmCompareSource> sources = ArmSources(options);
  const ArmLog log = ReadArmLog(options.log);
  ArmCompareOptions compare;
  if (!options.horizons.empty()) compare.horizons = options.horizons;

  Progress progress("compare", !options.quiet);
  const ArmCompareResult result = CompareArmLog(
      log, sources, compare, [&](long done, long total, const std::string& what) { progress.Update(done, total, what); });
  progress.Finish();

  OutputFiles files(options.out);
  files.Write("errors.csv", FormatArmSimulationScoresCsv(result.scores));
  files.Write("paths.csv", FormatArmComparePathsCsv(log, result));
  if (RenderingCompiled()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    files.WritePng("paths.png", ArmFreeRunImage(log, sources.front().model, result, options.plot_seconds, *renderer));
    if (std::any_of(result.scores.front().second.horizons.begin(), result.scores.front().second.horizons.end(),
                    [](const ArmHorizonScore& h) { return h.horizon > 0; }))
      files.WritePng("errors.png", RenderSeriesPlot(ArmErrorPlot(result), *renderer));
  } else {
    std::fprintf(stderr, "compare: warning: plots not drawn: %s\n", kRenderingNotCompiled);
  }
  if (!options.quiet) {
    std::printf("compared %d rows of %s (%g Hz) through %zu source(s)\n%s\n", log.rows(), options.log.c_str(),
                1.0 / log.sample_period, sources.size(), result.FullReport().c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

// The calibration predicts 63 frames ahead from every this many frames.
constexpr int kCalibrationStride = 4;

// A calibration's columns from horizon_frames on, and its CSV cells (empty scores without rows).
constexpr const char* kCalibrationColumns =
    "horizon_frames,seconds,rows,position_50,position_90,heading_50,heading_90,energy_score,"
    "constant_spread_energy_score,constant_spread,energy_gain,log_score\n";
void WriteCalibrationCells(const OmniCalibration& c, std::ostringstream* s) {
  *s << c.frames << "," << FormatCsvNumber(c.seconds) << "," << c.rows;
  for (double v : {c.position_50, c.position_90, c.heading_50, c.heading_90, c.energy_score, c.baseline_energy_score,
                   c.baseline_spread, c.EnergyGain(), c.log_score})
    *s << "," << (c.rows > 0 ? FormatCsvNumber(v) : std::string());
  *s << "\n";
}

// calibration.csv: one row per physics source and horizon.
std::string FormatCalibrationCsv(
    const std::vector<std::pair<const CompareSource*, std::vector<OmniCalibration>>>& calibration) {
  std::ostringstream s;
  s << "source,backend," << kCalibrationColumns;
  for (const auto& [source, rows] : calibration) {
    for (const OmniCalibration& c : rows) {
      s << source->label << "," << source->backend << ",";
      WriteCalibrationCells(c, &s);
    }
  }
  return s.str();
}

// spread_budget.csv: one row per physics source and horizon (analysis/omni_spread_budget.h).
std::string FormatSpreadBudgetCsv(
    const std::vector<std::pair<const CompareSource*, std::vector<OmniSpreadBudget>>>& budgets) {
  std::ostringstream s;
  s << "source,backend,horizon_frames,seconds,rows,measured,predicted,scale";
  for (const char* key : kOmniCovariancePartKeys) s << "," << key;
  s << ",camera,parameters\n";
  for (const auto& [source, rows] : budgets) {
    for (const OmniSpreadBudget& b : rows) {
      s << source->label << "," << source->backend << "," << b.frames << "," << FormatCsvNumber(b.seconds) << ","
        << b.rows << "," << FormatCsvNumber(b.measured) << "," << FormatCsvNumber(b.predicted) << ","
        << FormatCsvNumber(b.scale);
      for (double p : b.parts) s << "," << FormatCsvNumber(p);
      s << "," << FormatCsvNumber(b.camera) << "," << FormatCsvNumber(b.parameters) << "\n";
    }
  }
  return s.str();
}

// A calibration of one source's rows within [from, to) of the model's seen inputs.
struct DistanceCalibration {
  const CompareSource* source = nullptr;
  double from = 0, to = 0;
  std::vector<OmniCalibration> calibration;
};

std::string FormatDistanceCalibrationCsv(const std::vector<DistanceCalibration>& by_distance) {
  std::ostringstream s;
  s << "source,backend,distance_from,distance_to," << kCalibrationColumns;
  for (const DistanceCalibration& d : by_distance) {
    for (const OmniCalibration& c : d.calibration) {
      s << d.source->label << "," << d.source->backend << "," << FormatCsvNumber(d.from) << ","
        << (std::isfinite(d.to) ? FormatCsvNumber(d.to) : std::string("inf")) << ",";
      WriteCalibrationCells(c, &s);
    }
  }
  return s.str();
}

// A calibration of one source's rows by quarter of the log's turn rate, per horizon.
struct TurnRateCalibration {
  const CompareSource* source = nullptr;
  std::vector<std::array<OmniTurnQuarter, 4>> quarters;
};

std::string FormatTurnRateCalibrationCsv(const std::vector<TurnRateCalibration>& by_turn_rate) {
  std::ostringstream s;
  s << "source,backend,quarter,turn_rate_from,turn_rate_to," << kCalibrationColumns;
  for (const TurnRateCalibration& t : by_turn_rate) {
    for (std::size_t k = 0; k < 4; ++k) {
      for (const std::array<OmniTurnQuarter, 4>& horizon : t.quarters) {
        const OmniTurnQuarter& q = horizon[k];
        s << t.source->label << "," << t.source->backend << "," << k + 1 << ","
          << (q.calibration.rows > 0 ? FormatCsvNumber(q.from) + "," + FormatCsvNumber(q.to) : std::string(",")) << ",";
        WriteCalibrationCells(q.calibration, &s);
      }
    }
  }
  return s.str();
}

// Where each source's calibration goes.
struct SourceCalibrations {
  std::vector<std::pair<const CompareSource*, std::vector<OmniCalibration>>> whole;
  std::vector<DistanceCalibration> by_distance;
  std::vector<TurnRateCalibration> by_turn_rate;
  // Physics sources: where the spread of the position comes from (analysis/omni_spread_budget.h).
  std::vector<std::pair<const CompareSource*, std::vector<OmniSpreadBudget>>> budgets;
};

// The predictive distribution of every physics source (the observer's), and of every
// learned one whose predictor has a driving noise (its sampled rollouts), 4, 16 and 63
// frames ahead (analysis/omni_calibration.h, analysis/learned_noise.h); where the model
// knows the inputs its fit saw, the physics sources' split by how far from them; and
// every source's by quarter of the log's turn rate. With `parameter_uncertainty`, the
// model's parameters' own uncertainty widens them (ParameterShiftedModels; a linear
// predictor's weights drawn per rollout).
SourceCalibrations CalibrateSources(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& compare,
                                    bool parameter_uncertainty, Progress* progress) {
  const std::vector<std::array<OmniModel, 2>> parameter_shifts =
      parameter_uncertainty ? ParameterShiftedModels(model, log.frame_period) : std::vector<std::array<OmniModel, 2>>{};
  SourceCalibrations out;
  for (const CompareSource& s : compare.sources) {
    if (s.backend == "learned") {
      const auto& predictor = s.backend_options.predictor;
      if (!predictor || !predictor->info().has_driving_noise) continue;
      progress->Update(0, 1, s.label + ", calibration");
      LearnedNoiseOptions sampled;
      sampled.stride = kCalibrationStride;
      sampled.parameter_draws = parameter_uncertainty;
      out.by_turn_rate.push_back({&s, {}});
      std::vector<OmniDistanceCalibration> by_distance;
      out.whole.emplace_back(
          &s, CalibrateLearnedOmniLog(model, *predictor, log, sampled, &out.by_turn_rate.back().quarters, &by_distance));
      for (OmniDistanceCalibration& d : by_distance) out.by_distance.push_back({&s, d.from, d.to, std::move(d.calibration)});
      continue;
    }
    if (!IsKnownEngine(s.backend)) continue;
    progress->Update(0, 1, s.label + ", calibration");
    const std::vector<int> horizons{4, 16, 63};
    std::vector<OmniSpreadBudget> budgets;
    const auto rows =
        OmniLogPredictiveErrors(model, log, s.backend, horizons, kCalibrationStride, &budgets, parameter_shifts);
    out.whole.emplace_back(&s, CalibrateRows(rows, horizons, log.frame_period));
    out.budgets.emplace_back(&s, std::move(budgets));
    out.by_turn_rate.push_back({&s, CalibrateRowsByTurnRate(rows, horizons, log.frame_period)});
    // Where the model knows the inputs its fit saw: the same split by how far from them.
    if (model.observer.seen_inputs.empty()) continue;
    for (OmniDistanceCalibration& d : CalibrateRowsByDistance(rows, horizons, log.frame_period))
      out.by_distance.push_back({&s, d.from, d.to, std::move(d.calibration)});
  }
  return out;
}

// The calibration tables compare prints (not with --quiet).
void PrintCalibrations(const OmniModel& model, const SourceCalibrations& c) {
  for (const auto& [source, whole] : c.whole) {
    std::printf("calibration of %s's predictions (%s; energy score against the best constant spread on "
                "these rows):\n%s\n",
                source->label.c_str(), source->backend == "learned" ? "its sampled rollouts" : "the observer's",
                FormatCalibrationTable(whole).c_str());
  }
  for (const auto& [source, b] : c.budgets) {
    std::printf("where %s's predicted position spread comes from (RMS, mm; the parts add in squares to the "
                "filter's spread, which the model's safeguard scales; measured / predicted near 1 when calibrated):\n%s\n",
                source->label.c_str(), FormatSpreadBudgets(b).c_str());
  }
  for (const TurnRateCalibration& t : c.by_turn_rate) {
    std::printf("the same, %s, by quarter of the log's turn rate over each prediction (rad/s: position 50 / 90 %% "
                "ellipses hold):\n%s\n",
                t.source->label.c_str(), FormatTurnRateCalibrationTable(t.quarters).c_str());
  }
  for (const DistanceCalibration& d : c.by_distance) {
    if (std::none_of(d.calibration.begin(), d.calibration.end(), [](const OmniCalibration& k) { return k.rows > 0; }))
      continue;
    if (d.source->backend == "learned") {
      std::printf("the same, %s, predictions whose inputs went %s beyond its training range (1 is the range's span; "
                  "beyond 0.25 the learned backend counts a step as unseen):\n%s\n",
                  d.source->label.c_str(), CalibrationDistanceRange(d.from, d.to).c_str(),
                  FormatCalibrationTable(d.calibration).c_str());
      continue;
    }
    std::printf("the same, %s, predictions whose inputs lie %s from those %s's fit saw (observer.seen_inputs; 1 "
                "is a typical command's size):\n%s\n",
                d.source->label.c_str(), CalibrationDistanceRange(d.from, d.to).c_str(), model.name.c_str(),
                FormatCalibrationTable(d.calibration).c_str());
  }
}

int Compare(const CompareCliOptions& options) {
  // Check everything before running or writing anything.
  const RobotKind kind = ModelFileRobot(options.models.front());
  for (const std::string& path : options.models) {
    if (ModelFileRobot(path) != kind)
      throw InputError(SourceLocation{path}, "compare: every --model must be of one robot (the first is '" +
                                                 std::string(RobotKindName(kind)) + "')");
  }
  if (kind == RobotKind::kArm) return CompareArm(options);
  if (options.models.size() > 1)
    throw InputError("compare: an omni robot is compared on one --model (its backends side by side); got " +
                     std::to_string(options.models.size()));
  if (!options.horizons.empty()) throw InputError("compare: --horizon is for arm models (omni horizons are fixed)");
  const OmniModel model = LoadOmniModel(options.models.front());
  const OmniLog log = ReadOmniLogSayingHoles(options.log, options.select);
  const double frame_rate = 1.0 / log.frame_period;

  std::vector<std::shared_ptr<const OmniPredictor>> predictors;
  for (const std::string& path : options.predictors) predictors.push_back(std::make_shared<OmniPredictor>(OmniPredictor::Load(path)));
  const OmniCompareOptions compare = MakeCompareOptions(model, log, options.backends, predictors, options.predictors);

  Progress progress("compare", !options.quiet);
  const OmniCompareResult result = CompareOmniLog(
      model, log, compare, [&](long done, long total, const std::string& what) { progress.Update(done, total, what); });

  const SourceCalibrations calibrations =
      CalibrateSources(model, log, compare, options.parameter_uncertainty == "on", &progress);
  const auto& calibration = calibrations.whole;
  const auto& by_distance = calibrations.by_distance;
  progress.Finish();

  OutputFiles files(options.out);
  files.Write("errors.csv", FormatCompareErrorsCsv(result));
  files.Write("paths.csv", FormatComparePathsCsv(log, result));
  if (!calibration.empty()) files.Write("calibration.csv", FormatCalibrationCsv(calibration));
  if (!by_distance.empty()) files.Write("calibration_by_distance.csv", FormatDistanceCalibrationCsv(by_distance));
  if (!calibrations.budgets.empty()) files.Write("spread_budget.csv", FormatSpreadBudgetCsv(calibrations.budgets));
  if (!calibrations.by_turn_rate.empty())
    files.Write("calibration_by_turn_rate.csv", FormatTurnRateCalibrationCsv(calibrations.by_turn_rate));
  if (RenderingCompiled()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    files.WritePng("paths.png", RenderPathPlot(FreeRunPlot(log, result, model.name, options.plot_seconds), *renderer));
    files.WritePng("errors.png", RenderSeriesPlot(ErrorPlot(result, frame_rate), *renderer));
    for (const auto& [source, c] : calibration) {
      SeriesPlot pit = PitPlot(c, false);
      pit.title = source->label + ": " + pit.title;
      files.WritePng("calibration_" + source->label + ".png", RenderSeriesPlot(pit, *renderer));
    }
  } else {
    std::fprintf(stderr, "compare: warning: plots not drawn: %s\n", kRenderingNotCompiled);
  }

  if (!options.quiet) {
    std::printf("compared %zu rows of %s (%g fps) through %s, delay %d frames\n\n%s\n", log.rows.size(),
                options.log.c_str(), frame_rate, model.name.c_str(),
                model.command_delay_frames + model.vision_delay_frames, result.FullReport().c_str());
    PrintCalibrations(model, calibrations);
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddCompareCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<CompareCliOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare how well backends predict a measured log.");
  cmd->footer(
      "OMNI ROBOTS. Every backend replays the log (as 'twinsim replay' does) at six horizons: row i is predicted\n"
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
      "labelled 'learned' or 'residual' after their kind (and their file's name where two share one).\n"
      "\n"
      "ARMS. Every model (repeat --model: a URDF beside an identified model, say) on every --backend\n"
      "(default analytic; learned with --predictor, over the first model) is simulated open loop from\n"
      "the log's torques, in windows of each --horizon restarted from the logged q and qd, and in one\n"
      "free run over the whole log (horizon 0), beside holding the joints and constant velocity.\n"
      "Horizons the log is too short for are left out. Sources are named by backend, or model/backend.\n"
      "Outputs in DIR:\n"
      "  errors.csv  log,model,horizon,joint,windows,rows,diverged,rmse,fit,rmse_hold,rmse_constant_velocity,left_range\n"
      "              (rad or m, fit in %; model is the source's name; horizon 0 the free run;\n"
      "              left_range: windows in which a joint left its limits, which a real arm cannot)\n"
      "  paths.csv   t,measured_q1..measured_qn,<source>_q1..<source>_qn,... (the free runs; empty\n"
      "              cells outside them)\n"
      "  paths.png   per joint, measured and simulated q over the first --plot-seconds\n"
      "  errors.png  RMSE against horizon, every source and both baselines");
  cmd->add_option("--model", options->models,
                  "Model file (omni YAML; arm URDF or YAML). Arms: repeat to compare several models")
      ->required();
  cmd->add_option("--log", options->log,
                  "Measured log (CSV: omni t,x,y,theta,vx_cmd,vy_cmd,omega_cmd; arm t,q1..qn,tau1..taun)")
      ->required();
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->add_option("--backend", options->backends,
                  "Backend to compare (repeat --backend): ode, bullet, analytic or learned");
  cmd->add_option("--predictor", options->predictors,
                  "1-frame predictor for the learned backend (from twinsim train; repeat for several)");
  cmd->add_option("--horizon", options->horizons,
                  "Arm: a simulation window in s, 0 for the free run (repeat; default 0.05 0.1 0.25 0.5 1 2 0)")
      ->check(NonNegativeNumber());
  cmd->add_option("--plot-seconds", options->plot_seconds, "Seconds of the log drawn in paths.png")
      ->capture_default_str()
      ->check(PositiveNumber());
  AddParameterUncertaintyOption(cmd, &options->parameter_uncertainty);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  AddLogSelectorOptions(cmd, &options->select);
  cmd->callback([options, exit_code] { *exit_code = Compare(*options); });
}

}  // namespace twinsim
