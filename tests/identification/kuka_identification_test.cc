// Identification on real measurements: the KUKA LWR4+ logs of ../shared/realdata (skipped
// where that folder is absent). Identified on run1, judged on the held-out run2 and run3.
#include <gtest/gtest.h>

#include <filesystem>

#include "analysis/arm_identification.h"
#include "analysis/arm_replay.h"
#include "analysis/arm_simulation_score.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::string KukaDir() { return testing::SourcePath("../shared/realdata/kuka_lwr4"); }

TEST(KukaIdentification, HeldOutTorquesAreFarCloserThanTheUrdfs) {
  if (!std::filesystem::exists(KukaDir() + "/run1.csv")) GTEST_SKIP() << "no real data at " << KukaDir();
  const ArmModel urdf = LoadArmModel(KukaDir() + "/kuka_lwr4.urdf");
  const ArmLog run1 = ReadArmLog(KukaDir() + "/run1.csv");
  WlsIdentificationOptions options;
  options.torque_offsets = true;  // the torque sensors' biases, up to 0.86 N·m on joint 1
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(urdf, {run1}, options, &summary);
  EXPECT_EQ(identified.Validate(), "");
  EXPECT_EQ(summary.base_parameters, 57);
  EXPECT_LT(summary.condition_number, 200);
  for (const char* name : {"run2.csv", "run3.csv"}) {
    SCOPED_TRACE(name);
    const ArmLog log = ReadArmLog(KukaDir() + "/" + name);
    Eigen::MatrixXd tau = PredictArmTorques(identified, log);
    tau.rowwise() += summary.offsets.transpose();
    const TorqueErrors before = CompareArmTorques(urdf, log);
    const TorqueErrors after = CompareArmTorques(identified, log, tau);
    // Every joint closer than the URDF's CAD values, and on average by more than 40 %
    // (measured: 59 % -> 25 % of the torque RMS on run2, 70 % -> 37 % on run3); the
    // normalised error (RMS / twice the effort limit) below 0.2 % on run2 (0.158 %) and
    // 0.3 % on run3 (0.256 %), against the reference project's 0.18 %.
    for (int j = 0; j < 7; ++j) EXPECT_LT(after.error_rms[j], before.error_rms[j]) << "joint " << j + 1;
    EXPECT_LT(after.relative.mean(), 0.6 * before.relative.mean());
    EXPECT_LT(after.normalised, std::string(name) == "run2.csv" ? 0.002 : 0.003);
    std::printf("%s: mean relative error %.1f %% -> %.1f %%, normalised %.3f %% -> %.3f %%\n", name,
                100 * before.relative.mean(), 100 * after.relative.mean(), 100 * before.normalised,
                100 * after.normalised);
    // Its free run from the log's torques runs away (docs/identification.md); the score
    // holds the last finite state and stays a number (it once held a NaN state, and
    // identify --validate --report stopped with an internal error writing it).
    ArmSimulationScoreOptions free_run;
    free_run.horizons = {0};
    const ArmHorizonScore score = ScoreArmSimulation(identified, log, free_run).horizons.front();
    EXPECT_EQ(score.diverged, 1);
    EXPECT_TRUE(score.rmse.allFinite()) << score.rmse.transpose();
  }
}

TEST(KukaIdentification, WithoutOffsetsStillBeatsTheUrdfOnHeldOutData) {
  if (!std::filesystem::exists(KukaDir() + "/run1.csv")) GTEST_SKIP() << "no real data at " << KukaDir();
  const ArmModel urdf = LoadArmModel(KukaDir() + "/kuka_lwr4.urdf");
  const ArmModel identified = IdentifyArmByLeastSquares(urdf, {ReadArmLog(KukaDir() + "/run1.csv")}, {});
  const ArmLog run2 = ReadArmLog(KukaDir() + "/run2.csv");
  const TorqueErrors before = CompareArmTorques(urdf, run2);
  const TorqueErrors after = CompareArmTorques(identified, run2);
  // Measured 0.489 % -> 0.233 %: the offsets the model cannot hold remain in the error.
  EXPECT_LT(after.normalised, 0.6 * before.normalised);
}

// Issue 65's KUKA goal: fitted on run1, the model simulates run2 and run3 from their
// torques at least as well as the CAD model at 0.1 s and 1 s on every joint. The output
// error on 0.3 s windows (between the two horizons scored), started from the URDF (it
// simulates run1's windows better than the torque fit's estimate), reaches it on 27 of
// the 28 joint-horizon cells (run3 at 0.1 s: joint 2 58 % worse); on 0.1 s windows 25;
// started from the estimate, 15 (docs/identification.md, "A continuation"). Eight
// minutes on 2 cores: a deep test (tests/deep_only.txt).
TEST(KukaIdentification, OutputErrorFromTheUrdfSimulatesTheHeldOutRunsAsWellAsTheUrdf) {
  if (!std::filesystem::exists(KukaDir() + "/run1.csv")) GTEST_SKIP() << "no real data at " << KukaDir();
  const ArmModel urdf = LoadArmModel(KukaDir() + "/kuka_lwr4.urdf");
  ArmIdentificationOptions options;
  options.least_squares.torque_offsets = true;
  ArmOutputErrorOptions stage;
  stage.horizon = 0.3;
  options.output_error = {stage};
  ArmModel identified;
  const ArmIdentificationReport report =
      IdentifyArm(urdf, {ReadArmLog(KukaDir() + "/run1.csv")}, {}, options, &identified);
  EXPECT_TRUE(report.started_from_a_priori);
  EXPECT_TRUE(report.output_error.front().kept);
  int as_good = 0, cells = 0;
  double worst = 0;  // the largest ratio of the identified model's RMSE to the URDF's
  ArmSimulationScoreOptions windows;
  windows.horizons = {0.1, 1.0};
  for (const char* name : {"run2.csv", "run3.csv"}) {
    const ArmLog log = ReadArmLog(KukaDir() + "/" + name);
    const ArmSimulationScore cad = ScoreArmSimulation(urdf, log, windows);
    const ArmSimulationScore found = ScoreArmSimulation(identified, log, windows);
    for (std::size_t h = 0; h < 2; ++h)
      for (int j = 0; j < 7; ++j) {
        const double ratio = found.horizons[h].rmse[j] / cad.horizons[h].rmse[j];
        std::printf("%s %g s joint %d: %.4g against the URDF's %.4g (%.2fx)\n", name, windows.horizons[h], j + 1,
                    found.horizons[h].rmse[j], cad.horizons[h].rmse[j], ratio);
        as_good += ratio <= 1;
        ++cells;
        worst = std::max(worst, ratio);
      }
  }
  EXPECT_EQ(cells, 28);
  EXPECT_GE(as_good, 26);  // measured 27
  EXPECT_LT(worst, 1.8);   // measured 1.58 (run3, 0.1 s, joint 2)
}

}  // namespace
}  // namespace twinsim
