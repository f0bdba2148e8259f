// Changes of a robot's response part way through a log (a floor change, a robot that
// warms up, a second session in one file): the diagnosis's `changes` (CONTRACT.md).
//
// How strongly the robot responds is a scale s on what the model predicts: per row,
// y = s x + e, with x what the model says (its speed along its own direction of motion,
// or its turn rate) and y what the measurement says along the same direction. A change
// is a row where s jumps: binary segmentation (Scott and Knott, 1974) splits a stretch
// where the two scales fitted by least squares on either side leave the least squared
// error, keeps the split when the scales differ by at least `min_relative` of the larger
// and by `min_t` standard errors, and then searches each side again. The standard error
// counts the rows' correlation: the residual's Newey-West long-run variance (Bartlett
// kernel over `bandwidth_seconds`), sigma_lr^2 (1 / sum_1 x^2 + 1 / sum_2 x^2).
//
// `min_t` is the largest of many t statistics (every split point), so it is set far
// above a single test's 2: the 1 % critical value of Andrews' (1993) sup-Wald test for
// one parameter with 15 % trimming is 12.35 (|t| 3.5); 5 leaves room for the long-run
// variance's own error, and on the 60 single-floor Robotino runs flagged none (docs/
// diagnose.md, "Changes").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

struct ScaleChangeOptions {
  double min_segment_seconds = 1.0;  // each side of a change spans at least this
  double min_relative = 0.15;        // |s_after - s_before| / max(|s_before|, |s_after|)
  double min_t = 5.0;                // |s_after - s_before| / its long-run standard error
  double bandwidth_seconds = 1.0;    // the long-run variance's Bartlett window
};

struct ScaleChange {
  std::size_t row = 0;  // the first row of the new scale (an index into t, x, y)
  double t = 0;         // s, t[row]
  double before = 0, after = 0;
  double t_stat = 0;
};

// The changes of s in y = s x over rows at times t (ascending, nearly uniform), in time
// order. Rows with x = 0 carry no evidence and may be left out by the caller.
std::vector<ScaleChange> FindScaleChanges(const std::vector<double>& t, const std::vector<double>& x,
                                          const std::vector<double>& y, const ScaleChangeOptions& options = {});

// The changes in each log of how far and how fast the robot moves against what `model`
// predicts: the model runs freely from each log's start under its commands on `backend`
// (its body velocity depends on the commands alone), and the measured body velocity
// (poses differenced over about 0.3 s, measured frames only, in the measured robot
// frame) is regressed on it along its direction, on rows where the model moves at half
// its largest speed (turn rate) or more.
// A log on which the model's free run diverges is not searched; *notes (if given) hears
// which and why.
std::vector<ResponseChange> FindOmniResponseChanges(const OmniModel& model, const std::vector<OmniLog>& logs,
                                                    const std::string& backend,
                                                    const ScaleChangeOptions& options = {},
                                                    std::vector<std::string>* notes = nullptr);

}  // namespace twinsim
