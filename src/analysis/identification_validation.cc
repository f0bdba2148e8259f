#include "analysis/identification_validation.h"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "io/csv_table.h"

namespace twinsim {

namespace {

// The default horizons, those longer than a held-out log left out.
ArmSimulationScoreOptions HeldOutSimulation() {
  ArmSimulationScoreOptions options;
  options.drop_long_horizons = true;
  return options;
}

}  // namespace

IdentificationValidation ValidateIdentification(const ArmModel& a_priori, const ArmModel& identified,
                                                const WlsIdentificationSummary& summary,
                                                const WlsIdentificationOptions& options,
                                                const std::vector<ArmLog>& held_out) {
  IdentificationValidation validation;
  if (held_out.empty()) return validation;
  const BaseParameters base = IdentificationBase(a_priori, options);
  for (const ArmLog& log : held_out) {
    // The identified model's commands: its offsets (torque_offset effects) and the
    // a-priori model's delays and other kept effects included, as replay gives them.
    const Eigen::MatrixXd tau = PredictArmCommands(identified, log);
    Eigen::MatrixXd free = PredictBaseTorques(a_priori, base, summary.identified.head(summary.base_parameters), log);
    free += ExtraTorques(summary, summary.identified, log);
    const int first = log.edge_samples, last = log.rows() - log.edge_samples;
    HeldOutTorqueErrors errors;
    errors.path = log.path;
    errors.a_priori = CompareArmTorques(a_priori, log, first, last);
    errors.identified = CompareArmTorques(identified, log, tau, first, last);
    errors.unconstrained = CompareArmTorques(identified, log, free, first, last);
    validation.logs.push_back(std::move(errors));

    validation.simulated.emplace_back("a-priori", ScoreArmSimulation(a_priori, log, HeldOutSimulation()));
    validation.simulated.emplace_back("identified", ScoreArmSimulation(identified, log, HeldOutSimulation()));
  }
  return validation;
}

void AddSimulatedModel(IdentificationValidation* validation, const std::string& name, const ArmModel& model,
                       const std::vector<ArmLog>& held_out) {
  auto& simulated = validation->simulated;
  for (const ArmLog& log : held_out) {
    auto at = std::find_if(simulated.begin(), simulated.end(),
                           [&](const auto& s) { return s.first == "identified" && s.second.path == log.path; });
    simulated.emplace(at, name, ScoreArmSimulation(model, log, HeldOutSimulation()));
  }
}

std::string IdentificationValidation::FullReport() const {
  std::string text;
  char line[256];
  for (const HeldOutTorqueErrors& log : logs) {
    const TorqueErrors& before = log.a_priori;
    const TorqueErrors& after = log.identified;
    const TorqueErrors& unconstrained = log.unconstrained;
    text += "\nheld out: " + log.path + " (" + std::to_string(after.rows) + " rows)\n";
    std::snprintf(line, sizeof line, "%-6s %11s %21s %21s %21s\n", "joint", "torque RMS", "a-priori error",
                  "identified error", "(unconstrained)");
    text += line;
    for (Eigen::Index j = 0; j < after.torque_rms.size(); ++j) {
      std::snprintf(line, sizeof line, "%-6d %11.4g %11.4g (%6.2f%%) %11.4g (%6.2f%%) %11.4g (%6.2f%%)\n",
                    static_cast<int>(j) + 1, after.torque_rms[j], before.error_rms[j], 100 * before.relative[j],
                    after.error_rms[j], 100 * after.relative[j], unconstrained.error_rms[j],
                    100 * unconstrained.relative[j]);
      text += line;
    }
    std::snprintf(line, sizeof line,
                  "mean relative error %.2f%% -> %.2f%% (unconstrained %.2f%%); normalised (error / twice the effort "
                  "limit) %.3f%% -> %.3f%% (%.3f%%)\n",
                  100 * before.relative.mean(), 100 * after.relative.mean(), 100 * unconstrained.relative.mean(),
                  100 * before.normalised, 100 * after.normalised, 100 * unconstrained.normalised);
    text += line;
  }
  if (!simulated.empty()) text += FormatArmSimulationScores(simulated);
  return text;
}

std::string FormatIdentificationValidationCsv(const IdentificationValidation& validation) {
  std::string csv =
      "log,joint,torque_rms,error_a_priori,error_identified,error_unconstrained,relative_a_priori,"
      "relative_identified,relative_unconstrained\n";
  for (const HeldOutTorqueErrors& log : validation.logs) {
    const TorqueErrors& before = log.a_priori;
    const TorqueErrors& after = log.identified;
    const TorqueErrors& unconstrained = log.unconstrained;
    for (Eigen::Index j = 0; j < after.torque_rms.size(); ++j) {
      csv += log.path + "," + std::to_string(j + 1) + "," + FormatCsvNumber(after.torque_rms[j]) + "," +
             FormatCsvNumber(before.error_rms[j]) + "," + FormatCsvNumber(after.error_rms[j]) + "," +
             FormatCsvNumber(unconstrained.error_rms[j]) + "," + FormatCsvNumber(before.relative[j]) + "," +
             FormatCsvNumber(after.relative[j]) + "," + FormatCsvNumber(unconstrained.relative[j]) + "\n";
    }
  }
  return csv;
}

}  // namespace twinsim
