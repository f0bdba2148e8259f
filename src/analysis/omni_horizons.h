// Every horizon a simulator needs: several predictors (models through the replay, and
// the no-model baselines of omni_baselines.h) scored on the same rows at one horizon
// (identify's and diagnose's reports; docs/identification.md, "Every horizon").
//
//   std::vector<HorizonStretch> stretches = ...;  // logs, the rows that may be scored
//   std::vector<HorizonSum> s = ScoreHorizon(stretches, predictors, 60, options);
//   double rmse = s[1].PositionRmse();
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_replay.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// One predictor: a model replayed, or a baseline when model is null; with `learned`, the
// model's robot on the learned backend with that predictor (its own state, the tracker).
struct HorizonPredictor {
  std::string name;
  const OmniModel* model = nullptr;
  enum Baseline { kNone, kConstantVelocity, kIntegratedCommand } baseline = kNone;
  std::shared_ptr<const OmniPredictor> learned = nullptr;
};

// A log and which of its rows a prediction may end on (`scored`, one per row) and start
// from (rows from `first_start` on, at frames from `min_start_frame` on).
struct HorizonStretch {
  const OmniLog* log = nullptr;
  std::vector<char> scored;
  std::size_t first_start = 0;
  int min_start_frame = 0;
};

struct HorizonOptions {
  std::string backend = "analytic";
  OmniReplayState state = OmniReplayState::kObserver;
  double delay = 0;  // s, the integrated command's
  double radius = 0.09;  // m, weighs the heading error (a point on the rim)
  int threads = 0;
};

// Squared errors summed over the scored rows, in the robot frame of the measurement.
struct HorizonSum {
  double xy = 0, forward = 0, sideways = 0, turn = 0;  // m^2 (turn: r dtheta)
  long rows = 0;
  double PositionRmse() const;  // m
  double PoseRms() const;       // m, sqrt(dx^2 + dy^2 + (r dtheta)^2)
  void Add(const std::array<double, 3>& e);
  void Add(const HorizonSum& other);
};

// Each predictor's errors at `frames` ahead over the same rows: rows marked scored whose
// prediction starts on a logged frame at or after the stretch's start, and that every
// predictor predicts. Models predict from every (frames / 24)-th frame, so a 3 s horizon
// costs a few 4-frame ones. Stretches are replayed in parallel; the sums do not depend on
// the thread count. Throws as ReplayOmniLog.
std::vector<HorizonSum> ScoreHorizon(const std::vector<HorizonStretch>& stretches,
                                     const std::vector<HorizonPredictor>& predictors, int frames,
                                     const HorizonOptions& options);

// The seed's linear predictor (twinsim train --kind linear, one frame, rolled out by the
// learned backend) with `model`'s delay as its command lag, trained on the rows of `logs`
// marked in `rows` (one mask per log): what a user would try instead of the physics, for
// identify's and diagnose's every-horizon tables. Null, saying why in `notes`, where it
// cannot be trained (too few windows in the marked rows).
std::shared_ptr<const OmniPredictor> TrainLinearBaseline(const OmniModel& model, const std::vector<OmniLog>& logs,
                                                         std::vector<std::vector<char>> rows,
                                                         std::vector<std::string>* notes);

// ScoreHorizon, where the last of `predictors` may be a learned baseline that runs away
// on a scored row: then it is dropped from `predictors`, said in `notes`, and the rest
// are scored. Throws as ScoreHorizon otherwise.
std::vector<HorizonSum> ScoreHorizonWithoutRunaway(const std::vector<HorizonStretch>& stretches,
                                                   std::vector<HorizonPredictor>* predictors, int frames,
                                                   const HorizonOptions& options, std::vector<std::string>* notes);

// The note where the seed's linear predictor (trained on `trained_on`) predicts `scored_on`
// better than `model_name` at some horizon: `linear` and `model` are their errors (m) per
// horizon, labelled `labels`, over `rows` rows (a horizon without rows says nothing); ""
// when it is better nowhere.
std::string LinearPredictorWinsNote(const std::string& trained_on, const std::string& scored_on,
                                    const std::string& model_name, const std::vector<std::string>& labels,
                                    const std::vector<int>& rows, const std::vector<double>& linear,
                                    const std::vector<double>& model);

// A report's table of errors, predictors down and horizons across.
struct HorizonTable {
  std::vector<std::string> horizons;       // labels: "4 frames", "0.25 s", ...
  std::vector<std::string> predictors;
  std::vector<std::vector<double>> mm;     // [horizon][predictor], mm
  std::vector<int> rows;                   // per horizon
  // The predictor with the lowest error at horizon h (the first of equals); -1 without rows.
  int Best(std::size_t h) const;
};
// As text for a terminal (one decimal, "-" where a horizon has no rows, the best marked
// '*', a last line of row counts), and as an HTML <table> (the best in bold).
std::string FormatHorizonTable(const HorizonTable& table);
std::string FormatHorizonTableHtml(const HorizonTable& table);

// The horizons of the reports: `first` frames (the report's own), then 0.25 s, 1 s and
// 3 s rounded to frames, without repeats, each with its label ("4 frames", "0.25 s").
std::vector<std::pair<std::string, int>> ReportHorizons(int first, double frame_period);

}  // namespace twinsim
