// Held-out validation of an identified arm: the three models' errors, the printed
// table and validation.csv.
#include "analysis/identification_validation.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "identification/synthetic_arm_data.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(IdentificationValidation, TheIdentifiedModelBeatsTheAPrioriOneOnAHeldOutLog) {
  const testing::HeavierRrr c = testing::MakeHeavierRrr(LoadArmModel(testing::SourcePath("models/rrr.yaml")), 8.0);
  const ArmModel& a_priori = c.a_priori;
  const ArmLog& fit = c.fit;
  const ArmLog& held_out = c.held_out;
  const WlsIdentificationOptions options;
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(a_priori, {fit}, options, &summary);

  const IdentificationValidation v = ValidateIdentification(a_priori, identified, summary, options, {held_out});
  ASSERT_EQ(v.logs.size(), 1u);
  const HeldOutTorqueErrors& e = v.logs[0];
  EXPECT_EQ(e.identified.rows, held_out.rows() - 2 * held_out.edge_samples);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(e.identified.error_rms[j], 0.5 * e.a_priori.error_rms[j]) << "joint " << j + 1;
    EXPECT_LT(e.unconstrained.relative[j], 0.05) << "joint " << j + 1;  // the 1 % noise and little else
  }
  const std::string report = v.FullReport();
  EXPECT_EQ(report.rfind("\nheld out: held_out.csv (" + std::to_string(e.identified.rows) + " rows)\n", 0), 0u)
      << report;
  EXPECT_NE(report.find("mean relative error"), std::string::npos) << report;
  const std::string csv = FormatIdentificationValidationCsv(v);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "log,joint,torque_rms,error_a_priori,error_identified,error_unconstrained,relative_a_priori,"
            "relative_identified,relative_unconstrained");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);  // the header and 3 joints
  EXPECT_NE(csv.find("\nheld_out.csv,3,"), std::string::npos) << csv;
  // No held-out logs: nothing to report.
  EXPECT_EQ(ValidateIdentification(a_priori, identified, summary, options, {}).FullReport(), "");
}

}  // namespace
}  // namespace twinsim
