// The tables of an arm identification (identification/wls_identification.h) as the CSV
// files `twinsim identify --report` writes, numbers by FormatCsvNumber (io/csv_table.h):
//
//   parameters.csv  index,parameter,description,a_priori,identified,relative_std_pct,model
//                   one row per base parameter and estimated offset; commas in names
//                   and descriptions become ';'
//   joints.csv      joint,torque_rms,error_rms_a_priori,error_rms_identified,error_rms_model,offset
//                   N·m or N per joint; offset 0 when none was estimated
//
//   WriteFileAtomically("report/parameters.csv", FormatIdentifiedParametersCsv(summary));
#pragma once

#include <string>

#include "identification/wls_identification.h"

namespace twinsim {

// parameters.csv: each estimate beside its a-priori value, its relative standard
// deviation (%, "inf" where not finite) and the returned model's value.
std::string FormatIdentifiedParametersCsv(const WlsIdentificationSummary& summary);

// joints.csv: per joint the measured torque RMS, the three models' error RMS and the offset.
std::string FormatIdentifiedJointsCsv(const WlsIdentificationSummary& summary);

}  // namespace twinsim
