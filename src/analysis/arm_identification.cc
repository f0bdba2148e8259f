#include "analysis/arm_identification.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace twinsim {
namespace {

// The a-priori model as an output-error start: its inertia, friction and effects, with
// the least squares' torque offsets where those were estimated and its position torques
// (which stand beside the offsets: their first level is the offset's).
ArmModel APrioriStart(const ArmModel& a_priori, const ArmModel& least_squares, bool offsets) {
  ArmModel start = a_priori;
  start.effects.joints.resize(static_cast<std::size_t>(start.dof()));
  for (int j = 0; j < start.dof(); ++j) {
    JointEffects& e = start.effects.joints[static_cast<std::size_t>(j)];
    const JointEffects fitted = least_squares.effects.joint(j);
    if (offsets) e.torque_offset = fitted.torque_offset;
    if (fitted.torque_profile.on()) e.torque_profile = fitted.torque_profile;
  }
  return start;
}

// Where the first output-error stage started, and why.
std::string StartLine(const ArmIdentificationReport& r) {
  if (r.start_cost_a_priori <= 0) return "output error starts from the least squares' model";
  const bool run = r.output_error.front().whole_run;
  char line[400];
  std::snprintf(line, sizeof line,
                "output error starts from the %s model%s: its %s simulated at %.4g against %.4g for the %s model (%s)",
                r.started_from_a_priori ? "a-priori" : "least squares'",
                !r.started_from_a_priori                                      ? ""
                : r.least_squares.torque_knots > 0                            ? ", with the least squares' offsets and "
                                                                                "torques along the travel"
                : r.least_squares.offsets.size() > 0                          ? ", with the least squares' torque offsets"
                                                                               : "",
                run ? "shooting segments" : "fit windows",
                r.started_from_a_priori ? r.start_cost_a_priori : r.start_cost_least_squares,
                r.started_from_a_priori ? r.start_cost_least_squares : r.start_cost_a_priori,
                r.started_from_a_priori ? "least squares'" : "a-priori",
                run ? "each joint's squared error over its spread of q, summed"
                    : "each joint's error over constant velocity's, squared and summed");
  return line;
}

}  // namespace

ArmIdentificationReport IdentifyArm(const ArmModel& a_priori, const std::vector<ArmLog>& logs,
                                    const std::vector<ArmLog>& held_out, const ArmIdentificationOptions& options,
                                    ArmModel* identified) {
  if (!identified) throw std::invalid_argument("IdentifyArm: no model to fill");
  const auto start = std::chrono::steady_clock::now();
  ArmIdentificationReport report;
  report.inverse_dynamics = IdentifyArmByLeastSquares(a_priori, logs, options.least_squares, &report.least_squares);
  report.output_error.resize(options.output_error.size());
  ArmModel model = report.inverse_dynamics;
  if (!options.output_error.empty()) {
    const ArmOutputErrorOptions& first = options.output_error.front();
    report.start_cost_least_squares = ArmOutputErrorStartCost(model, logs, first);
    if (options.a_priori_start) {
      ArmModel start = APrioriStart(a_priori, model, options.least_squares.torque_offsets);
      report.start_cost_a_priori = ArmOutputErrorStartCost(start, logs, first);
      report.started_from_a_priori = report.start_cost_a_priori < report.start_cost_least_squares;
      if (report.started_from_a_priori) model = std::move(start);
    }
  }
  for (std::size_t k = 0; k < options.output_error.size(); ++k)
    model = RefineArmByOutputError(model, logs, options.output_error[k], &report.output_error[k]);
  report.validation =
      ValidateIdentification(a_priori, model, report.least_squares, options.least_squares, held_out);
  if (!options.output_error.empty())
    AddSimulatedModel(&report.validation, "inverse dynamics", report.inverse_dynamics, held_out);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  *identified = std::move(model);
  return report;
}

std::string ArmIdentificationReport::FullReport() const {
  std::string text = least_squares.FullReport();
  if (least_squares.offsets.size() > 0) {
    text += "torque offsets (measured - model), written as torque_offset effects with tau0 = -offset:";
    char value[32];
    for (Eigen::Index j = 0; j < least_squares.offsets.size(); ++j) {
      std::snprintf(value, sizeof value, " %.4g", least_squares.offsets[j]);
      text += value;
    }
    text += " N·m or N\n";
  }
  if (!output_error.empty()) text += "\n" + StartLine(*this) + "\n";
  for (std::size_t k = 0; k < output_error.size(); ++k) {
    if (output_error.size() > 1) {
      char stage[96];
      std::snprintf(stage, sizeof stage, "\nstage %zu of %zu of the continuation", k + 1, output_error.size());
      text += stage;
    }
    text += "\n" + output_error[k].FullReport();
  }
  return text + validation.FullReport() + "\n";
}

}  // namespace twinsim
