// What training says about itself: the options' check and the summary in words
// (OmniTrainOptions, OmniTrainSummary, OmniRolloutCheck in omni_predictor.h).
#include <cmath>
#include <sstream>
#include <string>

#include "learning/omni_predictor.h"

namespace twinsim {

bool OmniTrainOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (kind != "linear" && kind != "mlp") return fail("--kind must be linear or mlp, got '" + kind + "'");
  if (horizon < 1 || horizon > 30) return fail("--horizon must be 1 to 30 frames, got " + std::to_string(horizon));
  if (!(ridge >= 0) || !std::isfinite(ridge)) return fail("ridge must be finite and not negative");
  if (residual && kind == "linear" && residual_ridges.empty()) return fail("no residual ridge to try");
  for (double r : residual_ridges)
    if (!(r >= 0) || !std::isfinite(r)) return fail("residual ridges must be finite and not negative");
  if (validation_fraction <= 0 || validation_fraction >= 0.9) return fail("validation fraction must be in (0, 0.9)");
  if (residual) {
    if (nominal_engine != "analytic" && nominal_engine != "ode" && nominal_engine != "bullet")
      return fail("--nominal-engine must be analytic, ode or bullet, got '" + nominal_engine + "'");
    if (nominal_substeps < 0 || nominal_substeps > 1000)
      return fail("--nominal-substeps must be 1 to 1000 (or 0 to choose), got " + std::to_string(nominal_substeps));
    if (nominal_errors < 0 || nominal_errors > 30)
      return fail("nominal errors must be 0 to 30 frames, got " + std::to_string(nominal_errors));
  }
  if (members < 1 || members > kMostEnsembleMembers)
    return fail("--members must be 1 to " + std::to_string(kMostEnsembleMembers) + ", got " + std::to_string(members));
  if (members > 1 && kind != "mlp") return fail("--members is for --kind mlp (a linear predictor has its weights' uncertainty)");
  if (members > 1 && horizon != 1) return fail("--members is for a predictor of one frame ahead (--horizon 1)");
  if (kind == "mlp") return mlp.IsValid(why);
  return true;
}

std::string OmniTrainSummary::BriefReport() const {
  std::ostringstream s;
  s << samples << " samples (" << train_samples << " for training), position RMSE " << train_rmse * 1000
    << " mm on training, " << validation_rmse * 1000 << " mm held out, " << seconds << " s";
  if (validation_rollout_rmse > 0)
    s << "; on its own for 1 s: " << validation_rollout_rmse * 1000 << " mm held out";
  if (ridge.maxCoeff() > 0) s << "; " << RidgeChoice();
  if (chosen_state) s << "; " << StateChoice();
  if (!mlp_report.empty()) s << "; " << mlp_report;
  return s.str();
}

std::string OmniRolloutCheck::Describe() const {
  if (chosen == 0 || folds < 2) return "";
  static const char* const kOutputs[3] = {"forward", "sideways", "turn"};
  auto list = [](int mask) {
    std::string s;
    for (int j = 0; j < 3; ++j) {
      if (!(mask >> j & 1)) continue;
      const bool last = (mask >> (j + 1)) == 0;
      s += s.empty() ? "" : last ? " and " : ", ";
      s += kOutputs[j];
    }
    return s;
  };
  auto plural = [](int mask) { return __builtin_popcount(static_cast<unsigned>(mask)) > 1 ? "s" : ""; };
  const int dropped = chosen & ~kept;
  std::ostringstream s;
  s << "1 s rollouts over the " << folds << " folds ";
  if (dropped == 0) {
    s << "keep the " << list(kept) << " correction" << plural(kept) << " (" << rmse_kept * 1000 << " mm, "
      << rmse_none * 1000 << " mm without)";
  } else {
    s << "drop the " << list(dropped) << " correction" << plural(dropped) << " (" << rmse_chosen * 1000
      << " mm with, " << rmse_kept * 1000 << " mm without)";
  }
  return s.str();
}

std::string OmniTrainSummary::RidgeChoice() const {
  if (!(ridge.maxCoeff() > 0)) return "";
  std::ostringstream s;
  s << "ridge chosen by cross-validation over " << ridge_folds << " (forward, sideways, turn): ";
  for (int j = 0; j < 3; ++j) {
    s << (j ? ", " : "");
    if (std::isinf(ridge[j]))
      s << "no correction";
    else
      s << ridge[j];
  }
  if (const std::string check = rollout_check.Describe(); !check.empty()) s << "; " << check;
  return s.str();
}

std::string OmniTrainSummary::StateChoice() const {
  if (!chosen_state) return "";
  std::ostringstream s;
  s << "the model carried by its " << OmniReplayStateName(kept_state);
  if (!untrained_state.empty()) {
    s << " (" << untrained_state << ")";
  } else if (rollout_rmse_observer == 0 && rollout_rmse_tracker == 0) {
    s << " (no held-out 1 s rollout to choose by)";
  } else {
    s << " (held-out 1 s rollouts " << rollout_rmse_observer * 1000 << " mm from the observer's state, "
      << rollout_rmse_tracker * 1000 << " mm from the tracker's)";
  }
  return s.str();
}

}  // namespace twinsim
