#include "analysis/derivative_cutoff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "analysis/arm_replay.h"
#include "analysis/held_out_blocks.h"
#include "core/error.h"

namespace twinsim {

bool DerivativeCutoffOptions::IsValid(std::string* why) const {
  if (!(lowest_hz > 0 && std::isfinite(lowest_hz))) {
    std::ostringstream s;
    s << "the lowest cut-off must be a positive number of Hz, got " << lowest_hz;
    if (why) *why = s.str();
    return false;
  }
  return HeldOutChoiceOptions::IsValid(why);
}

bool HeldOutChoiceOptions::IsValid(std::string* why) const {
  std::ostringstream s;
  std::string inner;
  if (!(tolerance >= 0 && tolerance < 1)) {
    s << "the tolerance must lie in [0, 1), got " << tolerance;
  } else if (!(held_out > 0 && held_out < 1)) {
    s << "the held-out share must lie in (0, 1), got " << held_out;
  } else if (!(block_seconds >= 0 && std::isfinite(block_seconds))) {
    s << "the block length must be a non-negative number of seconds, got " << block_seconds;
  } else if (!identification.IsValid(&inner)) {
    s << inner;
  }
  if (why) *why = s.str();
  return s.str().empty();
}

std::string DerivativeCutoffChoice::Brief() const {
  if (cutoff_hz <= 0) return "derivatives: every log holds qd and qdd";
  std::ostringstream s;
  s << "derivative cut-off " << cutoff_hz << " Hz (held-out torque error per candidate:";
  for (std::size_t k = 0; k < candidates_hz.size(); ++k) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s %g Hz %.4g", k ? "," : "", candidates_hz[k], held_out_error[k]);
    s << buf;
  }
  s << ")";
  if (!note.empty()) s << "; " << note;
  return s.str();
}

double ArmHeldOutTorqueError(const ArmModel& model, const std::vector<ArmLog>& logs, const std::vector<int>& edge,
                             double block, double held_out, const Eigen::VectorXd& rest_speed) {
  const int n = model.dof();
  Eigen::VectorXd error = Eigen::VectorXd::Zero(n), torque = Eigen::VectorXd::Zero(n);
  for (std::size_t i = 0; i < logs.size(); ++i) {
    const ArmLog& log = logs[i];
    const Eigen::MatrixXd predicted = PredictArmCommands(model, log);
    Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> rest;
    if (rest_speed.size() > 0) rest = ArmRestRows(log, rest_speed);
    for (int r = edge[i]; r < log.rows() - edge[i]; ++r) {
      if (!InHeldOutBlock(log.t[r] - log.t[0], block, held_out)) continue;
      for (int j = 0; j < n; ++j) {
        if (rest.size() > 0 && rest(r, j)) continue;
        error[j] += (log.tau(r, j) - predicted(r, j)) * (log.tau(r, j) - predicted(r, j));
        torque[j] += log.tau(r, j) * log.tau(r, j);
      }
    }
  }
  double sum = 0;
  for (int j = 0; j < n; ++j) sum += torque[j] > 0 ? error[j] / torque[j] : 0;
  return sum / n;
}

int FirstCandidateNearBest(const std::vector<double>& errors, double tolerance) {
  double best = std::numeric_limits<double>::infinity();
  for (const double e : errors)
    if (std::isfinite(e)) best = std::min(best, e);
  for (std::size_t k = 0; k < errors.size() && std::isfinite(best); ++k) {
    if (errors[k] <= (1 + tolerance) * best) return static_cast<int>(k);
  }
  return -1;
}

DerivativeCutoffChoice ChooseDerivativeCutoff(const ArmModel& model, const std::vector<ArmLog>& logs,
                                              const DerivativeCutoffOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  DerivativeCutoffChoice choice;
  double rate = std::numeric_limits<double>::infinity();
  std::vector<double> durations;
  bool derived = false;
  for (const ArmLog& log : logs) {
    CheckArmLogMatchesModel(log, model);
    derived = derived || !log.qd_logged || !log.qdd_logged;
    rate = std::min(rate, (log.rows() - 1) / (log.t[log.rows() - 1] - log.t[0]));
    durations.push_back(log.t[log.rows() - 1] - log.t[0]);
  }
  if (!derived) return choice;
  const double block = HeldOutBlockSeconds(options.block_seconds, durations);
  for (double hz = options.lowest_hz; hz <= 0.25 * rate * (1 + 1e-9); hz *= 2) choice.candidates_hz.push_back(hz);
  if (choice.candidates_hz.empty()) choice.candidates_hz.push_back(options.lowest_hz);

  WlsIdentificationOptions identification = options.identification;
  identification.skip_filter_edges = false;  // ArmFitBlockLogs leaves the edges out
  std::vector<ArmLog> derived_logs = logs;
  std::vector<int> edge;  // per log: the first (lowest) candidate's edges, the widest
  for (double hz : choice.candidates_hz) {
    for (ArmLog& log : derived_logs) DeriveArmLog({hz}, &log);
    // Every candidate is scored on the rows the lowest cut-off leaves.
    if (edge.empty()) {
      for (const ArmLog& log : derived_logs) edge.push_back(log.edge_samples);
    }
    double error = std::numeric_limits<double>::quiet_NaN();
    try {
      const std::vector<ArmLog> fit = ArmFitBlockLogs(derived_logs, block, options.held_out);
      const ArmModel identified = IdentifyArmByLeastSquares(model, fit, identification);
      error = ArmHeldOutTorqueError(identified, derived_logs, edge, block, options.held_out);
    } catch (const InputError& e) {
      char at[48];
      std::snprintf(at, sizeof at, "at %g Hz: ", hz);
      if (choice.note.empty()) choice.note = at + std::string(e.what());
    }
    choice.held_out_error.push_back(error);
  }
  const int chosen = FirstCandidateNearBest(choice.held_out_error, options.tolerance);
  choice.cutoff_hz = chosen >= 0 ? choice.candidates_hz[static_cast<std::size_t>(chosen)] : options.lowest_hz;
  if (chosen < 0) choice.note = "no candidate could be identified, so the lowest is kept (" + choice.note + ")";
  return choice;
}

DerivativeCutoffChoice DeriveAtChosenCutoff(const ArmModel& model, std::vector<ArmLog>* logs,
                                            const DerivativeCutoffOptions& options) {
  const DerivativeCutoffChoice choice = ChooseDerivativeCutoff(model, *logs, options);
  if (choice.cutoff_hz > 0) {
    for (ArmLog& log : *logs) {
      if (log.derive_cutoff_hz != choice.cutoff_hz) DeriveArmLog({choice.cutoff_hz}, &log);
    }
  }
  return choice;
}

}  // namespace twinsim
