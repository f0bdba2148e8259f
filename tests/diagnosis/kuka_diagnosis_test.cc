// Diagnosis on real measurements: the KUKA LWR4+ logs of ../shared/realdata (skipped
// where that folder is absent), the URDF as given diagnosed on run1, the repaired model
// replayed on the unseen run2 and run3 (scripts/diagnose-kuka, docs/diagnose.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "analysis/arm_replay.h"
#include "diagnosis/arm_diagnosis.h"
#include "diagnosis/diagnosis_report.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::string KukaDir() { return testing::SourcePath("../shared/realdata/kuka_lwr4"); }

double AllJointsRms(const TorqueErrors& e) { return std::sqrt(e.error_rms.squaredNorm() / e.error_rms.size()); }

// Joint 5 carries 1.1 N·m RMS. A torque_saturation at 0.19 ± 0.29 N·m was named there
// before the limit had to be determined by the log: it "clipped" most commands to what
// the URDF says the motion needs, standing for a URDF that needs too little torque on
// that joint, and replay (which does not invert a limit) left the unseen runs' joint 5
// as it was. Now its limit is vetoed as undetermined and a Coulomb friction is named on
// joint 5 instead (measured: c_neg 1.27 ± 0.33, c_pos 0 ± 0.35 N·m), which carries over:
// run2's joint 5 0.944 -> 0.418 N·m, run3's 0.808 -> 0.668; all joints 1.006 -> 0.873
// and 0.987 -> 0.895 N·m (with the saturation 0.930 and 0.911).
TEST(KukaDiagnosis, NamesNoUndeterminedSaturationAndEveryRepairCarriesOverToUnseenRuns) {
  if (!std::filesystem::exists(KukaDir() + "/run1.csv")) GTEST_SKIP() << "no real data at " << KukaDir();
  const ArmModel urdf = LoadArmModel(KukaDir() + "/kuka_lwr4.urdf");
  ArmModel repaired;
  const DiagnosisReport report = DiagnoseArm(urdf, {ReadArmLog(KukaDir() + "/run1.csv")}, DiagnosisOptions{}, &repaired);
  SCOPED_TRACE(FormatDiagnosisTable(report));
  EXPECT_FALSE(report.effects.empty());
  for (const DiagnosedEffect& e : report.effects) {
    EXPECT_NE(e.name, "torque_saturation") << EffectLabel(e.name, e.joint);
    for (const auto& [key, error] : e.standard_errors) {
      if (std::isfinite(error)) {
        EXPECT_LT(error, 0.5) << EffectLabel(e.name, e.joint) << " " << key;
      }
    }
  }
  EXPECT_LT(report.gap_after, report.gap_before);
  for (const char* run : {"run2.csv", "run3.csv"}) {
    SCOPED_TRACE(run);
    const ArmLog log = ReadArmLog(KukaDir() + "/" + run);
    const TorqueErrors given = CompareArmTorques(urdf, log), diagnosed = CompareArmTorques(repaired, log);
    // Every joint the repair touches is closer on the unseen run, and all of them together
    // by at least 8 % (measured 13 % and 9 %).
    for (int j = 0; j < 7; ++j) EXPECT_LE(diagnosed.error_rms[j], given.error_rms[j] + 1e-9) << "joint " << j + 1;
    EXPECT_LT(AllJointsRms(diagnosed), 0.92 * AllJointsRms(given));
  }
}

}  // namespace
}  // namespace twinsim
