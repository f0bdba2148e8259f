// The real EMPS drive's estimation run (../shared/realdata/emps; skipped where that folder
// is absent), cut in halves: one half identified, the other simulated free from its force,
// as the benchmark scores a simulator (docs/identification.md, "Output error over whole
// runs"). The benchmark's validation run is kept back; these halves stand in for it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "analysis/arm_output_error.h"
#include "analysis/emps_like_plant.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::string EmpsDir() { return testing::SourcePath("../shared/realdata/emps"); }

// The estimation run's first (`second` false) or second half, as a log of its own.
ArmLog Half(bool second) {
  std::ifstream in(EmpsDir() + "/emps_est.csv");
  std::string header, line;
  std::getline(in, header);
  std::vector<std::string> rows;
  while (std::getline(in, line))
    if (!line.empty()) rows.push_back(line);
  const std::size_t middle = rows.size() / 2;
  std::ostringstream text;
  text << header << "\n";
  for (std::size_t r = second ? middle : 0; r < (second ? rows.size() : middle); ++r) text << rows[r] << "\n";
  ArmLogOptions options;
  options.cutoff_hz = 80;  // what identify's --cutoff auto chooses on either half
  return ParseArmLog(text.str(), second ? "emps_est second half" : "emps_est first half", options);
}

TEST(RealEmps, WholeRunOutputErrorOnTheEstimationRunsHalves) {
  if (!std::filesystem::exists(EmpsDir() + "/emps_est.csv")) GTEST_SKIP() << "no real data at " << EmpsDir();
  const ArmModel nominal = LoadArmModel(EmpsDir() + "/emps.urdf");
  WlsIdentificationOptions identification;
  identification.torque_offsets = true;
  ArmOutputErrorOptions options;
  options.whole_run = true;
  options.offsets = true;
  double offset[2], offset_se[2];  // each half's fitted offset tau0 and its standard error (N)
  for (bool second : {false, true}) {
    const ArmLog fit = Half(second), test = Half(!second);
    SCOPED_TRACE(fit.path);
    const ArmModel start = IdentifyArmByLeastSquares(nominal, {fit}, identification);
    ArmOutputErrorSummary summary;
    const ArmModel refined = RefineArmByOutputError(start, {fit}, options, &summary);
    const double before = testing::FreeRunFit(start, test), after = testing::FreeRunFit(refined, test);
    std::printf("%s: held-out quarter %.3g -> %.3g mm (%s); the other half's free run %.1f -> %.1f %%\n",
                fit.path.c_str(), 1e3 * summary.check_before[0], 1e3 * summary.check_after[0],
                summary.kept ? "kept" : "not kept", before, after);
    // Measured: first half 2.44 -> 2.34 mm, kept, the second half 92.1 -> 94.0 %; second
    // half 2.49 -> 2.75 mm, not kept (the estimate returned), the first half 90.8 %. The
    // halves' torque offsets differ by 0.27 N (quarters: -3.12, -3.20, -3.41, -3.44 N), a
    // drift no model of one run carries into the other.
    EXPECT_EQ(summary.kept, !second);
    EXPECT_GT(after, 90);
    if (summary.kept) {
      EXPECT_LT(summary.check_after[0], summary.check_before[0]);
      EXPECT_GT(after, before + 1);
    } else {
      EXPECT_EQ(after, before);  // the start, returned as it was
    }
    std::printf("%s", summary.FullReport().c_str());
    ASSERT_EQ(summary.standard_error.cols(), 4);
    offset[second] = summary.offset_after[0];
    offset_se[second] = summary.standard_error(0, 3);
  }
  // The drift, beyond what either fit's standard errors (each 2 s segment a cluster) allow
  // for: the halves' offsets differ by many of them.
  const double z = (offset[1] - offset[0]) / std::hypot(offset_se[0], offset_se[1]);
  std::printf("offsets %.4f and %.4f N, standard errors %.3g and %.3g: z = %.1f\n", offset[0], offset[1], offset_se[0],
              offset_se[1], z);
  EXPECT_GT(std::abs(z), 4);
}

}  // namespace
}  // namespace twinsim
