// Where a predicted position's spread comes from (issue 64): the observer's predictive
// covariance K frames ahead is a sum of parts (estimation/omni_observer.h,
// OmniCovariancePart: the start estimate carried on, the model's process noise, the
// driving noise, the drift) and the camera's; beside them, the measured error on the
// same rows. A model whose intervals are too wide shows which part makes them so.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "analysis/omni_replay.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// One horizon's budget over the rows predicted and measured. Every number is the square
// root of a mean over the rows of the trace of a position block (x, y; m), so they add in
// squares: sum_i parts_i^2 + parameters^2 + camera^2 = predicted^2. A calibrated model has measured near
// predicted (times the model's safeguard scale at K, where it has one: `scale`).
struct OmniSpreadBudget {
  int frames = 0;        // K
  double seconds = 0;    // K frame periods
  int rows = 0;
  double measured = 0;   // m, RMS of the measured position's distance from the predicted mean
  double predicted = 0;  // m, sqrt(mean tr(P_xy + R_xy)), P before the safeguard
  std::array<double, kCovarianceParts> parts{};  // m, sqrt(mean tr P_i,xy)
  double camera = 0;     // m, sqrt(tr R_xy)
  double scale = 1;      // the model's safeguard's position scale at K (observer.interval_scale)
  // m, sqrt(mean tr Σ_θ,xy): the parameters' own uncertainty where the replay drew it
  // (OmniReplayResult::parameter_covariance; in `predicted`, not scaled), else 0.
  double parameters = 0;
};

// The budget of `result` (a replay with covariance_parts) on `log` at `frames` ahead,
// over the rows that `keep` accepts (all when empty).
OmniSpreadBudget SpreadBudgetOf(const OmniLog& log, const OmniReplayResult& result, int frames,
                                const std::function<bool(std::size_t)>& keep = {});

// A log's budgets at several horizons: analysis/omni_calibration.h's
// OmniLogPredictiveErrors, with its `budgets`.

// The budgets pooled over several logs' (the same horizons, row-weighted).
std::vector<OmniSpreadBudget> PoolSpreadBudgets(const std::vector<std::vector<OmniSpreadBudget>>& per_log);

// A plain-text table: per horizon the measured error, the predicted spread and its parts
// (mm), and the ratio measured / predicted.
std::string FormatSpreadBudgets(const std::vector<OmniSpreadBudget>& budgets);

}  // namespace twinsim
