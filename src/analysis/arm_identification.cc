#include "analysis/arm_identification.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace twinsim {

ArmIdentificationReport IdentifyArm(const ArmModel& a_priori, const std::vector<ArmLog>& logs,
                                    const std::vector<ArmLog>& held_out, const ArmIdentificationOptions& options,
                                    ArmModel* identified) {
  if (!identified) throw std::invalid_argument("IdentifyArm: no model to fill");
  const auto start = std::chrono::steady_clock::now();
  ArmIdentificationReport report;
  report.inverse_dynamics = IdentifyArmByLeastSquares(a_priori, logs, options.least_squares, &report.least_squares);
  report.output_error.resize(options.output_error.size());
  ArmModel model = report.inverse_dynamics;
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
