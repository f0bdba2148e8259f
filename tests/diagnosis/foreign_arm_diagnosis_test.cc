// The arm's diagnosis on plants no one here wrote (issue 41): logs of the RRR arm made by
// MuJoCo (its own inverse dynamics and RK4, its own joint damping and friction loss in
// closed loop), encoders quantised at 2e-5 rad, white torque noise of 2 % of each
// joint's mean torque (the shoulder, carried by gravity, gets 0.3 N·m and more), torque
// noise that scales with the torque. The diagnosis gets models/rrr.yaml and the logs as
// CSV text; the tests alone know what the plant hides.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>

#include "diagnosis/arm_diagnosis.h"
#include "diagnosis/diagnosis_plants.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/mujoco_arm_plant.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {
namespace {

// Two logs of the plant (one seed pair per run), open loop or closed.
std::vector<ArmLog> ForeignLogs(const ArmModel& plant, int seed, testing::ForeignArmRecording how) {
  how.closed_loop = seed % 2 == 0;
  return {testing::RecordMujocoArm(plant, 2 * static_cast<std::uint64_t>(seed), how),
          testing::RecordMujocoArm(plant, 2 * static_cast<std::uint64_t>(seed) + 1, how)};
}

DiagnosisReport Diagnose(const std::vector<ArmLog>& logs) {
  const DiagnosisReport report = DiagnoseArm(testing::RrrWith(""), logs, DiagnosisOptions{});
  if (std::getenv("TWINSIM_PRINT_DIAGNOSIS")) std::cout << FormatDiagnosisTable(report);
  return report;
}

std::string Named(const DiagnosisReport& report) {
  std::string s;
  for (const DiagnosedEffect& e : report.effects) s += (s.empty() ? "" : ", ") + EffectLabel(e.name, e.joint);
  return s.empty() ? "nothing" : s;
}

TEST(ForeignArmPlant, MujocoAgreesWithTheModelOnACleanOpenLoopLog) {
  if (!testing::MujocoAvailable()) GTEST_SKIP() << "built without MuJoCo (libmujoco-dev)";
  testing::ForeignArmRecording how;
  how.noise_share = 0;
  how.quantum = 0;
  how.seconds = 10;
  const std::vector<ArmLog> logs = {testing::RecordMujocoArm(testing::RrrWith(""), 1, how)};
  const DiagnosisReport report = DiagnoseArm(testing::RrrWith(""), logs, testing::GapsOnly());
  // Without noise the only error left is the reader's derivative filter's.
  EXPECT_LT(report.gap_before, 0.05) << "N·m per joint";
}

// Clean logs: nothing is missing, so nothing may be named. The seeds on which the
// release before issue 41 named torque_saturation (3 of the 20 of seeds 1-20, open and
// closed loop: a limit clipping the noise's peaks); the diagnosis study runs all 20
// (TWINSIM_FOREIGN_SEEDS=20 runs them here).
TEST(ForeignArmPlant, CleanLogsNameNothing) {
  if (!testing::MujocoAvailable()) GTEST_SKIP() << "built without MuJoCo (libmujoco-dev)";
  std::vector<int> chosen = {14, 17, 20};
  if (const char* n = std::getenv("TWINSIM_FOREIGN_SEEDS")) {
    chosen.clear();
    for (int s = 1; s <= std::atoi(n); ++s) chosen.push_back(s);
  }
  const int seeds = static_cast<int>(chosen.size());
  int named = 0;
  for (int seed : chosen) {
    const DiagnosisReport report = Diagnose(ForeignLogs(testing::RrrWith(""), seed, {}));
    std::cout << "seed " << seed << ": " << Named(report) << " (test gap " << report.gap_before << " -> " << report.gap_after
              << ")\n";
    named += !report.effects.empty();
  }
  EXPECT_LE(named, seeds / 20) << named << " of " << seeds << " clean logs had an effect named";
}

// Clean logs under two more noise models: torque noise that scales with the torque (5 %
// of it, row by row, beside the white 2 %), and the white share made coloured (a first-
// order process of 20 ms: twenty rows at 1 kHz, longer than the derivative filter's
// span). Nothing is missing, so nothing may be named.
TEST(ForeignArmPlant, CleanLogsUnderProportionalAndColouredNoiseNameNothing) {
  if (!testing::MujocoAvailable()) GTEST_SKIP() << "built without MuJoCo (libmujoco-dev)";
  testing::ForeignArmRecording proportional, coloured;
  proportional.proportional_noise = 0.05;
  coloured.noise_correlation = 0.02;
  for (const auto& [label, how] : {std::pair<const char*, testing::ForeignArmRecording>{"proportional", proportional},
                                   std::pair<const char*, testing::ForeignArmRecording>{"coloured", coloured}}) {
    for (int seed : {1, 2}) {  // open loop, closed loop
      const DiagnosisReport report = Diagnose(ForeignLogs(testing::RrrWith(""), seed, how));
      EXPECT_TRUE(report.effects.empty()) << label << " noise, seed " << seed << ": " << Named(report);
    }
  }
}

// Hidden effects on the MuJoCo plant, their sizes off any grid: each named on its joint
// (outside the vocabulary: flagged unexplained there, or named) and closing at least 70 % of
// the test-row gap down to the plant's own: the nominal model's gap on the same seed's
// log recorded without the effect (the same noise, drawn in the same order).
struct ForeignCase {
  std::string label;
  std::string name;  // the vocabulary effect expected; "" outside the vocabulary
  int joint;         // 0-based, -1 for the payload
  testing::HiddenArmTorque hidden;
  std::string payload_yaml{};  // a payload the plant's links carry instead ("" none)
  std::string effects_yaml{};  // effects of the plant's own (a delay: the torque sent early) ("" none)
  std::map<std::string, double> parameters{};  // of the named effect, each within 10 %
};

void PrintTo(const ForeignCase& c, std::ostream* os) { *os << c.label; }

class ForeignArmEffect : public ::testing::TestWithParam<ForeignCase> {};

TEST_P(ForeignArmEffect, IsNamedOrFlaggedAndClosesTheGap) {
  if (!testing::MujocoAvailable()) GTEST_SKIP() << "built without MuJoCo (libmujoco-dev)";
  const ForeignCase& c = GetParam();
  testing::ForeignArmRecording how, clean;
  how.hidden = c.hidden;
  const ArmModel plant = c.payload_yaml.empty() ? testing::RrrWith(c.effects_yaml) : ArmPlantModel(testing::RrrWith(c.payload_yaml));
  const std::vector<ArmLog> logs = {testing::RecordMujocoArm(plant, 3, how), testing::RecordMujocoArm(plant, 5, how)};
  const std::vector<ArmLog> without = {testing::RecordMujocoArm(testing::RrrWith(""), 3, clean),
                                       testing::RecordMujocoArm(testing::RrrWith(""), 5, clean)};
  const DiagnosisReport report = Diagnose(logs);
  SCOPED_TRACE(FormatDiagnosisTable(report));
  const double floor = DiagnoseArm(testing::RrrWith(""), without, testing::GapsOnly()).gap_before;
  const double closed = (report.gap_before - report.gap_after) / (report.gap_before - floor);
  std::cout << c.label << ": " << Named(report) << ", closed " << closed << " (nominal " << report.gap_before
            << ", repaired " << report.gap_after << ", plant " << floor << ")\n";
  if (!c.name.empty()) {
    ASSERT_EQ(report.effects.size(), 1u) << Named(report);
    EXPECT_EQ(report.effects[0].name, c.name);
    EXPECT_EQ(report.effects[0].joint, c.joint);
    EXPECT_GE(closed, 0.7);
    for (const auto& [key, value] : c.parameters) {
      EXPECT_NEAR(report.effects[0].parameters.at(key), value, 0.1 * std::abs(value)) << key;
    }
  } else {
    const bool flagged = report.adequacy.size() == 3 && report.adequacy[static_cast<std::size_t>(c.joint)].unexplained;
    // Unexplained on its joint, or named by effects that close 70 %. A named effect
    // that closes less (a torque offset takes the spring's mean) must close something
    // and leave the joint flagged.
    EXPECT_TRUE(flagged || (!report.effects.empty() && closed >= 0.7)) << Named(report) << ", closed " << closed;
    if (!report.effects.empty()) {
      EXPECT_GT(closed, 0.0) << "a vocabulary effect named that makes the test rows worse";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Foreign, ForeignArmEffect,
    ::testing::Values(
        ForeignCase{"viscous_joint2", "viscous_friction", 1, testing::HiddenOnJoint(1, [](double, double qd) { return -0.43 * qd; })},
        ForeignCase{"coulomb_joint3", "coulomb_friction", 2,
                    testing::HiddenOnJoint(2, [](double, double qd) { return qd > 0 ? -0.37 : (qd < 0 ? 0.37 : 0.0); })},
        ForeignCase{"offset_joint1", "torque_offset", 0, testing::HiddenOnJoint(0, [](double, double) { return 0.62; })},
        ForeignCase{"payload", "payload", -1, {}, "  - {name: payload, joint: null, mass: 0.7, x: 0.33}\n"},
        // A delay on the base joint, which carries Coulomb friction: before issue 41's fix
        // the standstill rows were taken where the joint stands, not where the delayed
        // command reaches it, and the fit stopped at 16 ms (closing 51 %).
        ForeignCase{"delay_joint1", "time_delay", 0, {}, "", "  - {name: time_delay, joint: 1, delay: 0.021}\n",
                    {{"delay", 0.021}}},
        // A delay on the wrist, whose torque noise is a fifth of the elbow's: it moves the
        // error summed over joints by about 1 %. Before an effect on one joint was scored
        // on that joint's residual (issue 41), it was not named.
        ForeignCase{"delay_joint3", "time_delay", 2, {}, "", "  - {name: time_delay, joint: 3, delay: 0.0206}\n",
                    {{"delay", 0.0206}}},
        // Cogging (issue 41: named torque_saturation, closing 0 %) and a spring.
        ForeignCase{"cogging_joint1", "", 0, testing::HiddenOnJoint(0, [](double q, double) { return 0.5 * std::sin(6 * q); })},
        ForeignCase{"spring_joint2", "", 1, testing::HiddenOnJoint(1, [](double q, double) { return -4.0 * (q - 0.4); })}),
    [](const ::testing::TestParamInfo<ForeignCase>& info) { return info.param.label; });

}  // namespace
}  // namespace twinsim
