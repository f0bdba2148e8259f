// The real EMPS drive's estimation run (../shared/realdata/emps; skipped where that folder
// is absent), cut in halves: one half identified, the other simulated free from its force,
// as the benchmark scores a simulator (docs/identification.md, "Output error over whole
// runs"). The benchmark's validation run is kept back; these halves stand in for it.
#include <gtest/gtest.h>

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
  for (bool second : {false, true}) {
    const ArmLog fit = Half(second), test = Half(!second);
    SCOPED_TRACE(fit.path);
    const ArmModel start = IdentifyArm(nominal, {fit}, identification);
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
  }
}

}  // namespace
}  // namespace twinsim
