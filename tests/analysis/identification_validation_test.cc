// Held-out validation of an identified arm: the three models' errors, the printed
// table and validation.csv.
#include "analysis/identification_validation.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "identification/synthetic_arm_data.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A synthetic log as a reader gives it, qd and qdd derived from q.
ArmLog Read(const ArmLog& log, const std::string& path) { return ParseArmLog(FormatArmLog(log, false), path); }

TEST(IdentificationValidation, TheIdentifiedModelBeatsTheAPrioriOneOnAHeldOutLog) {
  const ArmModel a_priori = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  ArmModel truth = a_priori;  // heavier links, more viscous friction
  for (auto& j : truth.joints) j.child.mass *= 1.15, j.viscous *= 1.3;
  testing::SensorNoise noise;
  noise.torque_fraction = 0.01;
  const ArmLog fit = Read(testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 3), 8.0, 500.0, noise), "fit.csv");
  const ArmLog held_out =
      Read(testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 4), 4.0, 500.0, noise), "held_out.csv");
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
