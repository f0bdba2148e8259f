// Comparing sources of prediction (physics backends, a learned predictor) on one
// measured omni log (`twinsim compare`).
//
// Every source replays the log (omni_replay.h) at every horizon: K = 1 frame, 4 frames
// (the model's usual delay), 1 s (round(frame rate) frames) and a free run from the
// first row (K = 0). Each (source, horizon) gives the errors of the predicted rows
// against the measured poses; each source's free run is kept as a path to plot.
//
//   OmniCompareOptions options;
//   options.sources = {{"ode", "ode", {}}, {"analytic", "analytic", {}}};
//   options.horizons = DefaultCompareHorizons(1.0 / log.frame_period);
//   OmniCompareResult r = CompareOmniLog(model, log, options);
//   std::puts(r.FullReport().c_str());
//   WriteFileAtomically("errors.csv", FormatCompareErrorsCsv(r));
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_replay.h"
#include "learning/omni_predictor.h"
#include "backends/omni_backend_factory.h"
#include "core/pose.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// One thing that predicts: a backend, with its options.
struct CompareSource {
  std::string label;               // names the source in the outputs (letters, digits, '_', '-', '.')
  std::string backend;             // ode, bullet, analytic or learned
  OmniBackendOptions backend_options;  // the 1-frame predictor, for learned
};

struct OmniCompareOptions {
  std::vector<CompareSource> sources;
  std::vector<int> horizons;  // frames; 0 = free run
  // Also score the predictions of no model (analysis/omni_baselines.h) at every horizon
  // but the free run, as the sources "constant_velocity" and "integrated_command"
  // (backend "baseline"; the command at the model's delay), over the rows the first
  // source predicts there.
  bool baselines = false;

  // True when usable; else says why in *why (every problem, one per line).
  bool IsValid(std::string* why) const;
};

// The errors of one source's predictions at one horizon, over the predicted rows.
struct CompareErrorRow {
  std::string source;         // the source's label
  std::string backend;
  std::string horizon;        // "1 frame", "4 frames", "1 s", "free run"
  int horizon_frames = 0;     // K; 0 = free run
  int predicted = 0;          // rows predicted (the others held the measurement)
  double position_rmse = 0;   // m
  double position_max = 0;    // m
  double heading_rmse = 0;    // rad, differences wrapped to [-pi, pi)
  long bounded_steps = 0;     // learned: steps held to the predictor's training bounds
  long unseen_input_steps = 0;  // learned: steps whose inputs left the training range
  GripCheck grip;             // analytic: where its wheels needed more grip than they have
};

// One source's free run: the predicted pose at every log row (row 0 is the measurement).
struct ComparePath {
  std::string source;
  std::vector<double> t;    // s, one per log row
  std::vector<Pose2> pose;  // theta on the log's unwrapped branch
};

struct OmniCompareResult {
  std::vector<CompareErrorRow> rows;   // per source, per horizon, in the options' order
  std::vector<ComparePath> free_runs;  // per source, when the horizons include 0
  std::vector<int> horizons;           // as given
  double frame_rate = 0;               // Hz, of the log

  // The row of `source` at `horizon_frames`; nullptr when there is none.
  const CompareErrorRow* Find(const std::string& source, int horizon_frames) const;
  // A table: sources down, horizons across, position RMSE in mm and heading RMSE in
  // degrees.
  std::string FullReport() const;
};

// 1 frame, 4 frames, 0.25 s, 1 s, 3 s (rounded to frames) and free run (0), without
// repeats. Horizons longer than 1 s predict from every (K / 24)-th frame.
std::vector<int> DefaultCompareHorizons(double frame_rate);

// What `twinsim compare` runs on `log`: every backend of `backends` (empty: every
// physics engine built, plus learned when `predictor` is given) and the baselines at
// DefaultCompareHorizons, less those the log is too short for. Throws InputError when the predictor does not fit the model
// or the log's frame rate.
OmniCompareOptions MakeCompareOptions(const OmniModel& model, const OmniLog& log, std::vector<std::string> backends,
                                      const std::shared_ptr<const OmniPredictor>& predictor);
// The same with several 1-frame predictors (the seed's and a residual one, say): the
// learned backend once per predictor, labelled "learned" or "residual" after its kind,
// and where two would share a label, that followed by "-" and the file's name without
// its folder and extension ("learned-plant_mlp"). `predictor_paths` names them (in the
// same order; an empty path counts as "predictor").
OmniCompareOptions MakeCompareOptions(const OmniModel& model, const OmniLog& log, std::vector<std::string> backends,
                                      const std::vector<std::shared_ptr<const OmniPredictor>>& predictors,
                                      const std::vector<std::string>& predictor_paths);
// "free run", "1 frame", "0.25 s", "1 s", "3 s" (when frames is that many seconds
// rounded) or "K frames".
std::string HorizonLabel(int frames, double frame_rate);

// The errors of a replay's predicted rows against the log's poses (horizon fields left
// empty).
CompareErrorRow MeasurePredictionErrors(const OmniLog& log, const OmniReplayResult& result);

// Replays `log` through `model` on every source at every horizon. Checks every source
// first (builds its backend once) and throws InputError for invalid options, an
// unknown or uncompiled backend, a learned source without a fitting predictor, or a log
// too short for the longest horizon; CheckFailed when a model diverges. `progress`
// gets (done, total) in arbitrary units and what is running ("ode, 1 s").
OmniCompareResult CompareOmniLog(const OmniModel& model, const OmniLog& log, const OmniCompareOptions& options,
                                 const std::function<void(long, long, const std::string&)>& progress = {});

// errors.csv: `source,backend,horizon,horizon_frames,predicted,position_rmse,position_max,heading_rmse`.
std::string FormatCompareErrorsCsv(const OmniCompareResult& result);
// paths.csv: `t,measured_x,measured_y,measured_theta,<label>_x,<label>_y,<label>_theta,...`,
// one row per log row, the free run of every source.
std::string FormatComparePathsCsv(const OmniLog& log, const OmniCompareResult& result);

}  // namespace twinsim
