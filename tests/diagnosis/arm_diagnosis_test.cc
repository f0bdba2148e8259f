// Diagnosis of the RRR arm (seed 001) against plants with hidden effects: logs recorded
// from rrr.yaml plus effects, with quantised encoders and torque noise, q only (qd and
// qdd derived by the log reader). The diagnosis gets rrr.yaml and the logs; the test
// alone knows what was hidden, and uses the plant itself for the gap a perfect model
// reaches on the same held-out data.
#include "diagnosis/arm_diagnosis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdlib>
#include <iostream>

#include "core/error.h"
#include "diagnosis/diagnosis_plants.h"
#include "diagnosis/diagnosis_report.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_regressor.h"
#include "test_util.h"

namespace twinsim {
namespace {

struct Expected {
  std::string name;
  int joint = -1;  // 0-based; -1 for payload
  std::map<std::string, double> parameters;  // each within `tolerance`
  double tolerance = 0.15;                   // relative
};

struct ArmCase {
  std::string label;
  std::string hidden;  // the plant's effects (YAML list items)
  std::vector<Expected> expected;  // empty: nothing is missing
  double bandwidth = 10;           // Hz, the plant's computed-torque controller
  bool log_velocities = false;     // true: the log holds the exact qd and qdd
};

// Cases not met under the current rules, and why (measured): skipped with this message
// until the issue that owns them is resolved.
// TWINSIM_RUN_OPEN_FINDINGS=1 runs them anyway (to measure them again).
std::string OpenFinding(const std::string& label) {
  if (std::getenv("TWINSIM_RUN_OPEN_FINDINGS")) return "";
  if (label == "backlash_joint1") {
    return "issue 28: backlash is not seen. Joint 1's test RMS is 0.86 N·m, 3.0 times its noise (flexible joints with "
           "nothing missing reach 3.4); the memoryless learned residual removes 10 % (p 0.10) of bursts that follow each "
           "reversal; torque_saturation is named and closes 29 % (nominal 0.573, plant 0.337)";
  }
  if (label == "cogging_joint1") {
    return "issue 41: with the held-out blocks placed never-periodically the learned residual removes 18 % of joint "
           "1's test error (p 0.2), short of significance, and its RMS is 1.42 times its noise (4 flags on size "
           "alone). With the periodic placement before, which put fit and test blocks on the same phases of the "
           "trials, it removed 40 % (p 3e-10)";
  }
  return "";
}

void PrintTo(const ArmCase& c, std::ostream* os) { *os << c.label; }

std::vector<ArmCase> ArmCases() {
  return {
      {"clean", "", {}},
      {"viscous_small_joint2", "  - {name: viscous_friction, joint: 2, b: 0.5}\n", {{"viscous_friction", 1, {{"b", 0.5}}}}},
      {"viscous_large_joint3", "  - {name: viscous_friction, joint: 3, b: 1.5}\n", {{"viscous_friction", 2, {{"b", 1.5}}}}},
      {"coulomb_asymmetric_joint3", "  - {name: coulomb_friction, joint: 3, c_pos: 0.6, c_neg: 0.3}\n",
       {{"coulomb_friction", 2, {{"c_pos", 0.6}, {"c_neg", 0.3}}}}},
      {"coulomb_large_joint1", "  - {name: coulomb_friction, joint: 1, c: 2.0}\n",
       {{"coulomb_friction", 0, {{"c_pos", 2.0}, {"c_neg", 2.0}}}}},
      {"stribeck_joint2", "  - {name: stribeck_friction, joint: 2, c: 0.5, s: 1.5, vs: 0.1}\n",
       {{"stribeck_friction", 1, {{"c", 0.5}, {"s", 1.5}, {"vs", 0.1}}}}},
      {"offset_small_joint1", "  - {name: torque_offset, joint: 1, tau0: 0.5}\n", {{"torque_offset", 0, {{"tau0", 0.5}}}}},
      {"offset_large_joint3", "  - {name: torque_offset, joint: 3, tau0: -1.5}\n", {{"torque_offset", 2, {{"tau0", -1.5}}}}},
      // Delays under a gentler controller: at 10 Hz bandwidth 10 ms already drives the arm
      // into a limit cycle no derived acceleration resolves (measured, docs/diagnose.md).
      {"delay_18ms_joint2", "  - {name: time_delay, joint: 2, delay: 0.018}\n", {{"time_delay", 1, {{"delay", 0.018}}}}, 4},
      {"delay_25ms_joint2", "  - {name: time_delay, joint: 2, delay: 0.025}\n", {{"time_delay", 1, {{"delay", 0.025}}}}, 4},
      {"saturation_joint2", "  - {name: torque_saturation, joint: 2, limit: 12}\n", {{"torque_saturation", 1, {{"limit", 12}}}}},
      {"payload_small", "  - {name: payload, joint: null, mass: 0.3, x: 0.35}\n", {{"payload", -1, {{"mass", 0.3}, {"x", 0.35}}}}},
      {"payload_large", "  - {name: payload, joint: null, mass: 1.5, x: 0.35}\n", {{"payload", -1, {{"mass", 1.5}, {"x", 0.35}}}}},
      // The shipped flexible elbow (models/rrr_plant_flex.yaml), a 112 Hz resonance: seen
      // only where the log resolves it, here with the joint's logged velocity and
      // acceleration (derived at 10 Hz it is refused, docs/diagnose.md).
      {"flexibility_joint3", "  - {name: joint_flexibility, joint: 3, k: 5000, damping: 0.2, motor_inertia: 0.01}\n",
       {{"joint_flexibility", 2, {{"k", 5000}, {"motor_inertia", 0.01}}}}, 10, true},
      // Second sizes on other joints.
      {"stribeck_large_joint2", "  - {name: stribeck_friction, joint: 2, c: 0.8, s: 2.0, vs: 0.2}\n",
       {{"stribeck_friction", 1, {{"c", 0.8}, {"s", 2.0}, {"vs", 0.2}}}}},
      {"saturation_joint1", "  - {name: torque_saturation, joint: 1, limit: 6}\n", {{"torque_saturation", 0, {{"limit", 6}}}}},
      {"delay_25ms_joint1", "  - {name: time_delay, joint: 1, delay: 0.025}\n", {{"time_delay", 0, {{"delay", 0.025}}}}, 4},
      {"flexibility_soft_joint2", "  - {name: joint_flexibility, joint: 2, k: 3000, damping: 0.3, motor_inertia: 0.02}\n",
       {{"joint_flexibility", 1, {{"k", 3000}, {"motor_inertia", 0.02}}}}, 10, true},
      // Look-alikes hidden together: friction laws on one joint; a payload (follows
      // gravity and acceleration) with an offset (constant) on the joint it loads most.
      // Over the postures the task visits, a constant on joint 2 is partly what a shift of
      // the payload's centre of mass does, so the offset comes out within 25 %.
      {"coulomb_and_viscous_joint2",
       "  - {name: coulomb_friction, joint: 2, c: 0.8}\n  - {name: viscous_friction, joint: 2, b: 0.8}\n",
       {{"coulomb_friction", 1, {{"c_pos", 0.8}, {"c_neg", 0.8}}}, {"viscous_friction", 1, {{"b", 0.8}}}}},
      {"payload_and_offset_joint2",
       "  - {name: payload, joint: null, mass: 0.8, x: 0.35}\n  - {name: torque_offset, joint: 2, tau0: 0.6}\n",
       {{"payload", -1, {{"mass", 0.8}, {"x", 0.35}}}, {"torque_offset", 1, {{"tau0", 0.6}}, 0.25}}},
      {"payload_and_viscous_joint1",
       "  - {name: payload, joint: null, mass: 0.8, x: 0.35}\n  - {name: viscous_friction, joint: 1, b: 1.0}\n",
       {{"payload", -1, {{"mass", 0.8}, {"x", 0.35}}}, {"viscous_friction", 0, {{"b", 1.0}}}}},
  };
}

class ArmDiagnosisCase : public ::testing::TestWithParam<ArmCase> {};

TEST_P(ArmDiagnosisCase, NamesWhatWasHiddenAndClosesTheGap) {
  const ArmCase& c = GetParam();
  if (!OpenFinding(c.label).empty()) GTEST_SKIP() << OpenFinding(c.label);
  const ArmModel nominal = testing::RrrWith("");
  const ArmModel plant = testing::RrrWith(c.hidden);
  testing::ArmRecording noise;
  noise.bandwidth = c.bandwidth;
  noise.log_velocities = c.log_velocities;
  // One multi-sine (smooth, slow reversals) and one stop-and-go trial (stops, sharp
  // accelerations), 20 s each.
  const std::vector<ArmLog> logs = {testing::RecordArmPlant(plant, nominal, 1, 20, noise),
                                    testing::RecordArmPlant(plant, nominal, 2, 20, noise)};
  DiagnosisOptions options;
  ArmModel repaired;
  const DiagnosisReport report = DiagnoseArm(nominal, logs, options, &repaired);
  SCOPED_TRACE(FormatDiagnosisTable(report));
  if (std::getenv("TWINSIM_PRINT_DIAGNOSIS")) std::cout << FormatDiagnosisTable(report);

  ASSERT_EQ(report.effects.size(), c.expected.size());
  for (const Expected& want : c.expected) {
    const auto it = std::find_if(report.effects.begin(), report.effects.end(),
                                 [&](const DiagnosedEffect& e) { return e.name == want.name && e.joint == want.joint; });
    ASSERT_NE(it, report.effects.end()) << "expected " << EffectLabel(want.name, want.joint);
    if (want.name == "joint_flexibility") {
      // What a log determines is the resonance sqrt(k / J_m); k and J_m trade along it
      // (the report calls both undetermined). Measured: the soft joint's k 2329 and J_m
      // 0.0156 against 3000 and 0.02, the resonance 386 against 387 rad/s.
      const double found = std::sqrt(it->parameters.at("k") / it->parameters.at("motor_inertia"));
      const double hidden = std::sqrt(want.parameters.at("k") / want.parameters.at("motor_inertia"));
      EXPECT_NEAR(found, hidden, 0.05 * hidden) << "resonance, rad/s";
      for (const auto& [key, value] : want.parameters)
        EXPECT_NEAR(it->parameters.at(key), value, 0.3 * std::abs(value)) << want.name << " " << key;
    } else {
      for (const auto& [key, value] : want.parameters) {
        EXPECT_NEAR(it->parameters.at(key), value, want.tolerance * std::abs(value)) << want.name << " " << key;
      }
    }
    EXPECT_FALSE(it->evidence.empty());
  }
  // The plant's own gap on the same held-out rows: the floor a perfect model reaches.
  const DiagnosisReport own = DiagnoseArm(plant, logs, testing::GapsOnly(options));
  const double floor = own.gap_before;
  testing::RecordDiagnosis(report, floor);  // for docs/diagnose.md's counts
  if (c.expected.empty()) {
    EXPECT_EQ(report.gap_after, report.gap_before);
  } else {
    EXPECT_GE((report.gap_before - report.gap_after) / (report.gap_before - floor), 0.7)
        << "nominal " << report.gap_before << ", repaired " << report.gap_after << ", plant " << floor;
  }
  // Simulated from the torques on the test rows, the repaired model follows the motion:
  // its worst joint at least twice as close as the nominal's (measured 4 to 800 times
  // closer, 0.1 s windows), or within twice the plant's own where the effect barely acts
  // on those rows (a saturation the test rows never reach: the nominal is as good as the
  // plant there, 1.1e-4 rad, and a limit fitted 6 % low clips a little, 2.1e-4). Not the
  // flexible joints: a 112 Hz resonance simulated at the log's 1 kHz leaves both models
  // near constant velocity, the repaired one 1 to 9 % worse (measured; the report says
  // so in a note). A delay's repair closes less (measured 0.012 -> 0.0085 rad).
  ASSERT_FALSE(report.simulation.empty());
  ASSERT_EQ(own.simulation.size(), report.simulation.size());
  const DiagnosisSimulation& sim = report.simulation.front();
  EXPECT_EQ(sim.seconds, 0.1);
  EXPECT_GT(sim.windows, 20);
  const double nominal_worst = *std::max_element(sim.nominal.begin(), sim.nominal.end());
  const double repaired_worst = *std::max_element(sim.repaired.begin(), sim.repaired.end());
  const double plant_worst = *std::max_element(own.simulation.front().nominal.begin(), own.simulation.front().nominal.end());
  if (c.expected.empty()) {
    EXPECT_EQ(repaired_worst, nominal_worst);
  } else if (c.expected.front().name == "time_delay") {
    EXPECT_LT(repaired_worst, std::max(0.8 * nominal_worst, 2 * plant_worst));
  } else if (c.expected.front().name != "joint_flexibility") {
    EXPECT_LT(repaired_worst, std::max(0.5 * nominal_worst, 2 * plant_worst));
  }
  // The repaired model carries the effects, and reaches the same gap when diagnosed again.
  EXPECT_EQ(ListArmEffects(repaired.effects).size(), c.expected.size());
  EXPECT_NEAR(DiagnoseArm(repaired, logs, testing::GapsOnly(options)).gap_before, report.gap_after, 1e-9 * (1 + report.gap_after));
}

INSTANTIATE_TEST_SUITE_P(HiddenEffects, ArmDiagnosisCase, ::testing::ValuesIn(ArmCases()),
                         [](const ::testing::TestParamInfo<ArmCase>& info) { return info.param.label; });

// Effects outside the vocabulary: torques the plant receives beyond the command, which
// no model of the vocabulary can express. Each must come out as unexplained on its
// joint, or as vocabulary effects that close at least 70 % of the way to the plant's
// own gap; no effect may be named that closes less. The plant's gap: the nominal model
// on the same logs with the torque the plant received in place of the command.
struct OutsideCase {
  std::string label;
  int joint;  // 0-based, where the disturbance acts
  testing::JointTorque torque;
};

void PrintTo(const OutsideCase& c, std::ostream* os) { *os << c.label; }

class ArmOutsideVocabulary : public ::testing::TestWithParam<OutsideCase> {};

TEST_P(ArmOutsideVocabulary, ComesOutUnexplainedOnItsJoint) {
  const OutsideCase& c = GetParam();
  if (!OpenFinding(c.label).empty()) GTEST_SKIP() << OpenFinding(c.label);
  const ArmModel nominal = testing::RrrWith("");
  testing::ArmRecording noise;
  noise.disturbance = testing::OnJoint(c.joint, c.torque);
  std::vector<ArmLog> received(2);
  const std::vector<ArmLog> logs = {testing::RecordArmPlant(nominal, nominal, 1, 20, noise, &received[0]),
                                    testing::RecordArmPlant(nominal, nominal, 2, 20, noise, &received[1])};
  const DiagnosisReport report = DiagnoseArm(nominal, logs, DiagnosisOptions{});
  SCOPED_TRACE(FormatDiagnosisTable(report));
  if (std::getenv("TWINSIM_PRINT_DIAGNOSIS")) std::cout << FormatDiagnosisTable(report);
  const double floor = DiagnoseArm(nominal, received, testing::GapsOnly()).gap_before;
  testing::RecordDiagnosis(report, floor);
  const double closed = (report.gap_before - report.gap_after) / (report.gap_before - floor);
  ASSERT_EQ(report.adequacy.size(), 3u);
  const bool flagged = report.adequacy[static_cast<std::size_t>(c.joint)].unexplained;
  EXPECT_TRUE(flagged || (!report.effects.empty() && closed >= 0.7))
      << "closed " << closed << " of the way (nominal " << report.gap_before << ", repaired " << report.gap_after
      << ", plant " << floor << ")";
  if (!report.effects.empty()) {
    EXPECT_GE(closed, 0.7) << "a vocabulary effect named that closes too little";
  }
  for (std::size_t j = 0; j < report.adequacy.size(); ++j) {
    if (static_cast<int>(j) != c.joint) {
      EXPECT_FALSE(report.adequacy[j].unexplained) << "joint " << j + 1;
    }
  }
  if (flagged) {
    EXPECT_NE(DiagnosisVerdict(report).find("Unexplained: on joint " + std::to_string(c.joint + 1)), std::string::npos);
  }
}

INSTANTIATE_TEST_SUITE_P(
    OutsideVocabulary, ArmOutsideVocabulary,
    ::testing::Values(
        // Cogging: a motor's magnets pull the rotor towards N rest positions per turn.
        OutsideCase{"cogging_joint2", 1, [](double q, double) { return 0.6 * std::sin(12 * q); }},
        // Cogging on the base joint, a finer pitch.
        OutsideCase{"cogging_joint1", 0, [](double q, double) { return 0.4 * std::sin(20 * q); }},
        // A gravity-compensation spring on the shoulder, k 4 N·m/rad about 0.4 rad. Before
        // the boosted learner it went unflagged in 2 of 5 study runs (docs/diagnose.md).
        OutsideCase{"spring_joint2", 1, [](double q, double) { return -4.0 * (q - 0.4); }},
        // Backlash: a 0.15 kg m^2 part with 0.02 rad of play either way on the base
        // joint, striking 15 Hz stops at each reversal (state and a dead band).
        OutsideCase{"backlash_joint1", 0, testing::Backlash(0.15, 0.02, 15, 0.2, 0.001)}),
    [](const ::testing::TestParamInfo<OutsideCase>& info) { return info.param.label; });

// --refit-model: the model's own parameters re-identified on the fit blocks first. A
// hidden payload then goes into the last link's identified inertial parameters and is
// not named; the held-out gap still reaches the plant's own. The default (trusting the
// model) names it (payload_large above). Omni robots refuse the option.
TEST(ArmDiagnosis, RefitModelAbsorbsAPayloadIntoTheLinkParameters) {
  const ArmModel nominal = testing::RrrWith("");
  const ArmModel plant = testing::RrrWith("  - {name: payload, joint: null, mass: 1.5, x: 0.35}\n");
  const std::vector<ArmLog> logs = {testing::RecordArmPlant(plant, nominal, 1, 20),
                                    testing::RecordArmPlant(plant, nominal, 2, 20)};
  DiagnosisOptions options;
  options.refit_model = true;
  ArmModel repaired;
  const DiagnosisReport report = DiagnoseArm(nominal, logs, options, &repaired);
  SCOPED_TRACE(FormatDiagnosisTable(report));
  if (std::getenv("TWINSIM_PRINT_DIAGNOSIS")) std::cout << FormatDiagnosisTable(report);
  const double floor = DiagnoseArm(plant, logs, testing::GapsOnly()).gap_before;
  const double given = DiagnoseArm(nominal, logs, testing::GapsOnly()).gap_before;
  testing::RecordDiagnosis(report, floor);
  RecordProperty("refit_gap", FormatParameter(report.refit_gap));
  EXPECT_DOUBLE_EQ(report.gap_before, given);  // the gap before is the given model's
  ASSERT_TRUE(std::isfinite(report.refit_gap));
  EXPECT_GE((given - report.refit_gap) / (given - floor), 0.9) << given << " " << report.refit_gap << " " << floor;
  EXPECT_LE(report.gap_after, report.refit_gap);
  for (const DiagnosedEffect& e : report.effects) EXPECT_NE(e.name, "payload");
  EXPECT_EQ(repaired.effects.payload_mass, 0);
  EXPECT_NE(FormatDiagnosisJson(report).find("\"refit_gap\""), std::string::npos);
  EXPECT_NE(DiagnosisVerdict(report).find("Refitting the model's own parameters"), std::string::npos);
}

TEST(ArmDiagnosis, PointMassParametersGiveThePayloadsTorques) {
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  ArmModel loaded = rrr;
  AddArmEffect({"payload", -1, {{"mass", 0.7}, {"x", 0.3}, {"y", -0.05}, {"z", 0.1}}}, rrr.dof(), &loaded.effects);
  const Eigen::Vector3d q(0.3, -0.4, 1.1), qd(0.5, -1.0, 0.7), qdd(2.0, 1.0, -3.0);
  const Eigen::VectorXd difference = InverseDynamics(ArmPlantModel(loaded), q, qd, qdd, false) -
                                     InverseDynamics(rrr, q, qd, qdd, false);
  const Eigen::MatrixXd y = Regressor(rrr, q, qd, qdd);
  const Eigen::VectorXd from_regressor =
      y.middleCols(kParametersPerLink * (rrr.dof() - 1), kParametersPerLink) *
      PointMassParameters(0.7, Eigen::Vector3d(0.3, -0.05, 0.1));
  EXPECT_LT((difference - from_regressor).norm(), 1e-9 * (1 + difference.norm()));
}

TEST(ArmDiagnosis, RefusesLogsThatDoNotFitTheModel) {
  const ArmModel rrr = testing::RrrWith("");
  const ArmLog two_joints = ParseArmLog("t,q1,q2,tau1,tau2\n0,0,0,0,0\n0.001,0,0,0,0\n0.002,0,0,0,0\n", "two.csv");
  try {
    DiagnoseArm(rrr, {two_joints}, {});
    FAIL() << "a two-joint log was accepted for a three-joint arm";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("two.csv:1:"), std::string::npos) << e.what();
  }
  // Two seconds hold no held-out block of the automatic length beside a fit block.
  const ArmLog short_log = testing::RecordArmPlant(rrr, rrr, 1, 0.4);
  try {
    DiagnoseArm(rrr, {short_log}, {});
    FAIL() << "a 0.4 s log was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("too short"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twinsim
