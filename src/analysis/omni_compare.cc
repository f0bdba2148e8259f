#include "analysis/omni_compare.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "analysis/omni_baselines.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "engines/omni_engine.h"
#include "io/csv_table.h"

namespace twinsim {
namespace {

constexpr double kRadToDeg = 180.0 / kPi;

bool IsLabelChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
         c == '.';
}

// Every how many frames a horizon predicts from: every frame up to 1 s, then every
// (K / 24)-th (a 3 s horizon would cost 45 times a 4-frame one).
int StrideOf(int horizon, double frame_rate) {
  return horizon > std::lround(frame_rate) ? std::max(1, horizon / 24) : 1;
}

// Replay work of one run, in frames stepped: the estimate plus K frames per prediction.
long RunWeight(const OmniLog& log, int horizon, double frame_rate) {
  const long frames = log.FrameIndex(log.rows.size() - 1) + 1;
  return frames * (1 + horizon / StrideOf(horizon, frame_rate));
}

// The first frame a prediction `horizon` frames ahead can end on.
int FirstPredictedFrame(const OmniModel& model, const OmniLog& log, int horizon) {
  const int delay = model.command_delay_frames + model.vision_delay_frames;
  return std::max(delay, log.FrameIndex(1)) + kWarmUpFrames + horizon;
}

}  // namespace

bool OmniCompareOptions::IsValid(std::string* why) const {
  std::ostringstream problems;
  if (sources.empty()) problems << "no source to compare\n";
  std::set<std::string> labels;
  for (const CompareSource& s : sources) {
    if (s.label.empty() || !std::all_of(s.label.begin(), s.label.end(), IsLabelChar))
      problems << "source label '" << s.label << "' must be letters, digits, '_', '-' or '.'\n";
    else if (s.label == "measured" || s.label == "t")
      problems << "source label '" << s.label << "' is taken by the measured columns\n";
    else if (!labels.insert(s.label).second)
      problems << "source '" << s.label << "' given twice\n";
  }
  if (horizons.empty()) problems << "no horizon to compare at\n";
  std::set<int> seen;
  for (int k : horizons) {
    if (k < 0) problems << "horizon must be 0 (free run) or more frames, got " << k << "\n";
    else if (!seen.insert(k).second) problems << "horizon " << k << " given twice\n";
  }
  std::string out = problems.str();
  if (out.empty()) return true;
  out.pop_back();
  if (why) *why = out;
  return false;
}

const CompareErrorRow* OmniCompareResult::Find(const std::string& source, int horizon_frames) const {
  for (const CompareErrorRow& r : rows)
    if (r.source == source && r.horizon_frames == horizon_frames) return &r;
  return nullptr;
}

std::string OmniCompareResult::FullReport() const {
  // Sources down, horizons across; a cell is "RMSE mm / RMSE deg".
  std::vector<std::string> sources;
  for (const CompareErrorRow& r : rows)
    if (std::find(sources.begin(), sources.end(), r.source) == sources.end()) sources.push_back(r.source);
  std::size_t first_width = std::string("source").size();
  for (const auto& s : sources) first_width = std::max(first_width, s.size());
  std::vector<std::vector<std::string>> cells(sources.size(), std::vector<std::string>(horizons.size(), "-"));
  std::vector<std::size_t> widths(horizons.size());
  for (std::size_t h = 0; h < horizons.size(); ++h) {
    widths[h] = HorizonLabel(horizons[h], frame_rate).size();
    for (std::size_t s = 0; s < sources.size(); ++s) {
      const CompareErrorRow* r = Find(sources[s], horizons[h]);
      if (r && r->predicted > 0) {
        char cell[64];
        std::snprintf(cell, sizeof cell, "%.1f / %.2f", r->position_rmse * 1000, r->heading_rmse * kRadToDeg);
        cells[s][h] = cell;
      }
      widths[h] = std::max(widths[h], cells[s][h].size());
    }
  }
  std::ostringstream out;
  out << "position RMSE (mm) / heading RMSE (deg) of the predicted rows, by prediction horizon\n";
  auto pad = [](const std::string& s, std::size_t w) { return s + std::string(w - s.size(), ' '); };
  auto lpad = [](const std::string& s, std::size_t w) { return std::string(w - s.size(), ' ') + s; };
  out << pad("source", first_width);
  for (std::size_t h = 0; h < horizons.size(); ++h) out << "   " << lpad(HorizonLabel(horizons[h], frame_rate), widths[h]);
  out << "\n";
  for (std::size_t s = 0; s < sources.size(); ++s) {
    out << pad(sources[s], first_width);
    for (std::size_t h = 0; h < horizons.size(); ++h) out << "   " << lpad(cells[s][h], widths[h]);
    out << "\n";
  }
  // The grip once per source, from the horizon where most steps passed it (each
  // horizon simulates the same tracking and its own predictions).
  auto share = [](const GripCheck& g) { return g.steps > 0 ? static_cast<double>(g.beyond) / static_cast<double>(g.steps) : 0.0; };
  std::map<std::string, GripCheck> grips;
  for (const CompareErrorRow& r : rows) {
    GripCheck& g = grips[r.source];
    if (share(r.grip) > share(g)) g = r.grip;
  }
  for (const std::string& source : sources) {
    if (const std::string grip = DescribeGrip(grips[source]); !grip.empty()) out << "note: " << source << ": " << grip << "\n";
  }
  for (const CompareErrorRow& r : rows) {
    if (r.bounded_steps > 0) {
      out << "note: " << r.source << " at " << r.horizon << ": the learned predictor left the range of its training data on "
          << r.bounded_steps << " steps, each held to " << kBoundFactor << "x the largest step it was trained on\n";
    }
    if (r.unseen_input_steps > 0) {
      out << "note: " << r.source << " at " << r.horizon << ": on " << r.unseen_input_steps
          << " steps the learned predictor's inputs lay beyond its training data's range (extrapolation)\n";
    }
  }
  return out.str();
}

std::vector<int> DefaultCompareHorizons(double frame_rate) {
  std::vector<int> out;
  for (int k : {1, 4, static_cast<int>(std::lround(frame_rate / 4)), static_cast<int>(std::lround(frame_rate)),
                static_cast<int>(std::lround(3 * frame_rate)), 0})
    if (k >= 0 && std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
  return out;
}

std::string HorizonLabel(int frames, double frame_rate) {
  if (frames == 0) return "free run";
  if (frames == 1) return "1 frame";
  if (frames == std::lround(frame_rate / 4)) return "0.25 s";
  if (frames == std::lround(frame_rate)) return "1 s";
  if (frames == std::lround(3 * frame_rate)) return "3 s";
  return std::to_string(frames) + " frames";
}

CompareErrorRow MeasurePredictionErrors(const OmniLog& log, const OmniReplayResult& result) {
  CompareErrorRow out;
  double sum_position = 0, sum_heading = 0;
  for (std::size_t i = 0; i < result.t.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i)) continue;
    const Pose2& p = result.pose[i];
    const Pose2& m = log.rows[i].pose;
    const double d2 = (p.x - m.x) * (p.x - m.x) + (p.y - m.y) * (p.y - m.y);
    const double dtheta = WrapAngle(p.theta - m.theta);
    sum_position += d2;
    sum_heading += dtheta * dtheta;
    out.position_max = std::max(out.position_max, std::sqrt(d2));
    ++out.predicted;
  }
  if (out.predicted > 0) {
    out.position_rmse = std::sqrt(sum_position / out.predicted);
    out.heading_rmse = std::sqrt(sum_heading / out.predicted);
  }
  return out;
}

// (twinsim::HorizonLabel below: in a unity batch omni_calibration_report.cc's file-local
// HorizonLabel would hide it inside this anonymous namespace.)
namespace {

// Builds every source's backend, so a bad name or predictor fails before any runs, and refuses a log too short for
// the longest horizon.
void CheckCompareSourcesAndHorizons(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& options) {
  const double frame_rate = 1.0 / log.frame_period;
  FrameTiming timing;
  timing.frame_rate = frame_rate;
  timing.physics_substeps = DefaultPhysicsSubsteps(frame_rate);
  FieldModel field;
  field.walls = false;
  for (const CompareSource& s : options.sources) MakeOmniBackend(s.backend, {model}, field, timing, s.backend_options);

  // A horizon no row can be predicted at would report nothing; say so instead. The
  // replay's tracker starts at frame D (or the second row) and predicts K frames ahead
  // once it has run kWarmUpFrames.
  const int delay = model.command_delay_frames + model.vision_delay_frames;
  const int last_frame = log.FrameIndex(log.rows.size() - 1);
  const int longest = *std::max_element(options.horizons.begin(), options.horizons.end());
  const int needed = FirstPredictedFrame(model, log, longest);
  if (longest > 0 && last_frame < needed) {
    std::ostringstream msg;
    msg << "log of " << last_frame + 1 << " frames is too short to compare at the "
        << twinsim::HorizonLabel(longest, frame_rate) << " horizon (" << longest << " frames): needs at least "
        << needed + 1 << " frames (delay " << delay << ", warm-up " << kWarmUpFrames << ", horizon " << longest << ")";
    throw InputError(SourceLocation{log.path}, msg.str());
  }
}

// Adds the constant-velocity and integrated-command baselines' rows, scored on the rows the first source predicted.
void AddCompareBaselineRows(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& options,
                            const std::vector<std::vector<bool>>& first_predicted, OmniCompareResult* out) {
  for (const char* name : {"constant_velocity", "integrated_command"}) {
    for (std::size_t h = 0; h < options.horizons.size(); ++h) {
      const int k = options.horizons[h];
      if (k == 0) continue;
      OmniReplayResult result = std::string(name) == "constant_velocity"
                                    ? ConstantVelocityPrediction(log, k)
                                    : IntegratedCommandPrediction(log, k, model.TotalDelaySeconds(log.frame_period));
      for (std::size_t i = 0; i < result.predicted.size(); ++i) {
        result.predicted[i] = result.predicted[i] && first_predicted[h][i];
      }
      CompareErrorRow row = MeasurePredictionErrors(log, result);
      row.source = name;
      row.backend = "baseline";
      row.horizon = twinsim::HorizonLabel(k, out->frame_rate);
      row.horizon_frames = k;
      out->rows.push_back(row);
    }
  }
}

}  // namespace

OmniCompareResult CompareOmniLog(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& options,
                                 const std::function<void(long, long, const std::string&)>& progress) {
  if (std::string problem; !options.IsValid(&problem)) throw InputError(problem);
  const double frame_rate = 1.0 / log.frame_period;
  // Every source must build before any runs, and the log must be long enough for the longest horizon.
  CheckCompareSourcesAndHorizons(model, log, options);

  long total = 0;
  for (std::size_t s = 0; s < options.sources.size(); ++s)
    for (int k : options.horizons) total += RunWeight(log, k, frame_rate);

  OmniCompareResult out;
  out.horizons = options.horizons;
  out.frame_rate = frame_rate;
  long done = 0;
  std::vector<std::vector<bool>> first_predicted(options.horizons.size());  // the first source's rows, per horizon
  for (const CompareSource& source : options.sources) {
    for (std::size_t h = 0; h < options.horizons.size(); ++h) {
      const int k = options.horizons[h];
      OmniReplayOptions replay;
      replay.backend = source.backend;
      replay.backend_options = source.backend_options;
      replay.horizon = k;
      replay.stride = StrideOf(k, frame_rate);
      replay.stride_origin = 0;  // every source (observer or tracker) predicts from the same frames
      const long weight = RunWeight(log, k, frame_rate);
      const std::string what = source.label + ", " + HorizonLabel(k, frame_rate);
      const OmniReplayResult result = ReplayOmniLog(model, log, replay, [&](int d, int t) {
        if (progress && t > 0) progress(done + weight * std::min(d, t) / t, total, what);
      });
      done += weight;

      CompareErrorRow row = MeasurePredictionErrors(log, result);
      row.bounded_steps = result.bounded_steps;
      row.unseen_input_steps = result.unseen_input_steps;
      row.grip = result.grip;
      row.source = source.label;
      row.backend = source.backend;
      row.horizon = HorizonLabel(k, frame_rate);
      row.horizon_frames = k;
      out.rows.push_back(row);
      if (k == 0) out.free_runs.push_back({source.label, result.t, result.pose});
      if (first_predicted[h].empty()) first_predicted[h] = result.predicted;
    }
  }
  if (options.baselines) AddCompareBaselineRows(model, log, options, first_predicted, &out);
  if (progress) progress(total, total, "");
  return out;
}

std::string FormatCompareErrorsCsv(const OmniCompareResult& result) {
  std::ostringstream out;
  out << "source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse\n";
  for (const CompareErrorRow& r : result.rows)
    out << r.source << "," << r.backend << "," << r.horizon << "," << r.horizon_frames << "," << r.predicted << ","
        << FormatCsvNumber(r.position_rmse) << "," << FormatCsvNumber(r.position_max) << ","
        << FormatCsvNumber(r.heading_rmse) << "\n";
  return out.str();
}

std::string FormatComparePathsCsv(const OmniLog& log, const OmniCompareResult& result) {
  std::ostringstream out;
  out << "t,measured_x,measured_y,measured_theta";
  for (const ComparePath& p : result.free_runs) out << "," << p.source << "_x," << p.source << "_y," << p.source << "_theta";
  out << "\n";
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const OmniLogRow& m = log.rows[i];
    out << FormatCsvNumber(m.t) << "," << FormatCsvNumber(m.pose.x) << "," << FormatCsvNumber(m.pose.y) << ","
        << FormatCsvNumber(m.pose.theta);
    for (const ComparePath& p : result.free_runs)
      out << "," << FormatCsvNumber(p.pose[i].x) << "," << FormatCsvNumber(p.pose[i].y) << ","
          << FormatCsvNumber(p.pose[i].theta);
    out << "\n";
  }
  return out.str();
}

OmniCompareOptions MakeCompareOptions(const OmniModel& model, const OmniLog& log, std::vector<std::string> backends,
                                      const std::shared_ptr<const OmniPredictor>& predictor) {
  if (!predictor) return MakeCompareOptions(model, log, std::move(backends), {}, {});
  return MakeCompareOptions(model, log, std::move(backends), {predictor}, {""});
}

OmniCompareOptions MakeCompareOptions(const OmniModel& model, const OmniLog& log, std::vector<std::string> backends,
                                      const std::vector<std::shared_ptr<const OmniPredictor>>& predictors,
                                      const std::vector<std::string>& predictor_paths) {
  const double frame_rate = 1.0 / log.frame_period;
  for (const auto& p : predictors) p->CheckUse(model, frame_rate, 1, "compare of " + log.path);
  if (backends.empty()) {
    backends = AvailableOmniEngines();
    if (!predictors.empty()) backends.push_back("learned");
  }
  // One label per predictor: its kind, made unique by its file's name where needed.
  std::vector<std::string> labels;
  for (const auto& p : predictors) labels.push_back(p->residual() ? "residual" : "learned");
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (std::count(labels.begin(), labels.end(), labels[i]) < 2) continue;
    const std::string base = labels[i];
    for (std::size_t j = i; j < labels.size(); ++j) {
      if (labels[j] != base) continue;
      const std::string path = j < predictor_paths.size() ? predictor_paths[j] : "";
      std::string stem = std::filesystem::path(path).stem().string();
      for (char& c : stem)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '_';
      labels[j] = base + "-" + (stem.empty() ? "predictor" + std::to_string(j + 1) : stem);
    }
  }
  OmniCompareOptions compare;
  compare.baselines = true;
  // The default horizons the log is long enough for (the 1-frame one always, so that a
  // log too short for anything is still told so).
  for (int k : DefaultCompareHorizons(frame_rate)) {
    if (k <= 1 || FirstPredictedFrame(model, log, k) <= log.FrameIndex(log.rows.size() - 1)) compare.horizons.push_back(k);
  }
  for (const std::string& b : backends) {
    if (b != "learned" || predictors.empty()) {
      compare.sources.push_back({b, b, OmniBackendOptions{}});
      continue;
    }
    for (std::size_t i = 0; i < predictors.size(); ++i)
      compare.sources.push_back({labels[i], b, OmniBackendOptions{predictors[i]}});
  }
  return compare;
}

}  // namespace twinsim
