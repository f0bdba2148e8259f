#include "identification/identification_csv.h"

#include <algorithm>
#include <cmath>

#include "io/csv_table.h"

namespace twinsim {
namespace {

// A CSV field without a separator in it.
std::string NoCommas(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  return s;
}

}  // namespace

std::string FormatIdentifiedParametersCsv(const WlsIdentificationSummary& summary) {
  std::string csv = "index,parameter,description,a_priori,identified,relative_std_pct,model\n";
  for (std::size_t k = 0; k < summary.names.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    csv += std::to_string(k + 1) + "," + NoCommas(summary.names[k]) + "," + NoCommas(summary.descriptions[k]) + "," +
           FormatCsvNumber(summary.a_priori[i]) + "," + FormatCsvNumber(summary.identified[i]) + "," +
           (std::isfinite(summary.relative_std[i]) ? FormatCsvNumber(summary.relative_std[i]) : "inf") + "," +
           FormatCsvNumber(summary.consistent[i]) + "\n";
  }
  return csv;
}

std::string FormatIdentifiedJointsCsv(const WlsIdentificationSummary& summary) {
  std::string joints = "joint,torque_rms,error_rms_a_priori,error_rms_identified,error_rms_model,offset\n";
  for (int j = 0; j < summary.dof; ++j) {
    joints += std::to_string(j + 1) + "," + FormatCsvNumber(summary.torque_rms[j]) + "," +
              FormatCsvNumber(summary.error_rms_a_priori[j]) + "," + FormatCsvNumber(summary.error_rms_identified[j]) +
              "," + FormatCsvNumber(summary.error_rms_model[j]) + "," +
              FormatCsvNumber(summary.offsets.size() ? summary.offsets[j] : 0.0) + "\n";
  }
  return joints;
}

}  // namespace twinsim
