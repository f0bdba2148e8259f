#include "analysis/position_friction_choice.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "analysis/held_out_blocks.h"
#include "core/error.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {

bool PositionFrictionChoiceOptions::IsValid(std::string* why) const {
  std::ostringstream s;
  if (candidates.empty()) s << "no knots to choose from";
  for (const int k : candidates) {
    if (s.str().empty() && k != 0 && !(k >= 2 && k <= kMaxProfileKnots))
      s << (torque ? "a position torque" : "position friction") << " needs 2 to " << kMaxProfileKnots
        << " knots (or 0: none), got " << k;
  }
  if (!s.str().empty()) {
    if (why) *why = s.str();
    return false;
  }
  return HeldOutChoiceOptions::IsValid(why);
}

std::string PositionFrictionChoice::Brief() const {
  std::ostringstream s;
  const char* none = torque ? "none" : "one level";
  s << (torque ? "position torque: " : "position friction: ")
    << (knots > 0 ? std::to_string(knots) + " knots" : std::string(none))
    << " (held-out torque error per candidate:";
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s %d %.4g", k ? "," : "", candidates[k], held_out_error[k]);
    s << buf;
  }
  s << ")";
  if (!note.empty()) s << "; " << note;
  return s.str();
}

PositionFrictionChoice ChoosePositionFrictionKnots(const ArmModel& model, const std::vector<ArmLog>& logs,
                                                   const PositionFrictionChoiceOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  PositionFrictionChoice choice;
  choice.torque = options.torque;
  choice.candidates = options.candidates;
  std::vector<double> durations;
  std::vector<int> edge;
  for (const ArmLog& log : logs) {
    CheckArmLogMatchesModel(log, model);
    durations.push_back(log.t[log.rows() - 1] - log.t[0]);
    edge.push_back(log.edge_samples);
  }
  const double block = HeldOutBlockSeconds(options.block_seconds, durations);
  const std::vector<ArmLog> fit = ArmFitBlockLogs(logs, block, options.held_out);
  WlsIdentificationOptions identification = options.identification;
  identification.skip_filter_edges = false;  // ArmFitBlockLogs leaves the edges out
  // Scored where the fit reads friction: on the rows where the joint moves.
  const Eigen::VectorXd rest_speed = ArmRestSpeeds(logs, identification.rest_share, identification.decimate);
  for (const int knots : options.candidates) {
    (options.torque ? identification.position_torque_knots : identification.position_friction_knots) = knots;
    double error = std::numeric_limits<double>::quiet_NaN();
    try {
      error = ArmHeldOutTorqueError(IdentifyArmByLeastSquares(model, fit, identification), logs, edge, block,
                                    options.held_out, rest_speed);
    } catch (const InputError& e) {
      if (choice.note.empty()) choice.note = "with " + std::to_string(knots) + " knots: " + e.what();
    }
    choice.held_out_error.push_back(error);
  }
  const int chosen = FirstCandidateNearBest(choice.held_out_error, options.tolerance);
  if (chosen >= 0) {
    choice.knots = choice.candidates[static_cast<std::size_t>(chosen)];
  } else {
    choice.note = std::string("no candidate could be identified, so ") +
                  (options.torque ? "no position torque is fitted (" : "one level is kept (") + choice.note + ")";
  }
  return choice;
}

}  // namespace twinsim
