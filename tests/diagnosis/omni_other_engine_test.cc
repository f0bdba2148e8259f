// Omni plants from another engine (issue 41): clean random drives recorded by ODE, whose
// wheels slip in the fastest turns, diagnosed on the analytic model, which cannot slip.
// Nothing may be named, and the report must say where the analytic model left its
// validity (a wheel needing more grip than it has; engines/omni_engine.h, GripCheck).
#include <gtest/gtest.h>

#include "diagnosis/diagnosis_plants.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "engines/omni_engine.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(OmniOtherEngine, CleanOdeLogsNameNothingOnTheAnalyticModelAndSayWhereItDoesNotHold) {
  if (AvailableOmniEngines().size() < 2) GTEST_SKIP() << "needs ODE";
  // Measured (2026-11-29): 30 s drives up to 1.5 m/s and 3 m/s^2 inward; the analytic
  // model passes its grip on 1.3 to 6.2 % of the steps (up to 1.5 times it). On seed 2 a
  // traction_limit removes 41 % of the selection rows' error, all of it in 1 of the 4
  // blocks it changes (not significant): no effect.
  for (int seed = 1; seed <= 4; ++seed) {
    OmniModel plant = testing::Omni4();
    plant.vision_noise_xy = 0.001;
    plant.vision_noise_theta = 0.005;
    const OmniLog log = testing::RecordLog(plant, testing::RandomDrive(1.5, 3, 1.5), 30, seed, "ode", "ode.csv");
    const DiagnosisReport report = DiagnoseOmni(testing::Omni4(), {log}, DiagnosisOptions{});
    SCOPED_TRACE(FormatDiagnosisTable(report));
    EXPECT_TRUE(report.effects.empty()) << "seed " << seed;
    bool said = false;
    for (const std::string& note : report.notes) said = said || note.find("needed more grip than they have") != std::string::npos;
    EXPECT_TRUE(said) << "seed " << seed;
  }
}

}  // namespace
}  // namespace twinsim
