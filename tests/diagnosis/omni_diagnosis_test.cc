// Diagnosis of the omni robot against plants with hidden effects: 30 s random drives of
// omni4 plus effects, seen by a camera with 1 mm and 0.005 rad noise at 30 fps. The
// diagnosis gets omni4.yaml and the logs; the test alone knows what was hidden, and
// uses the plant itself for the gap a perfect model reaches on the same held-out data.
#include "diagnosis/omni_diagnosis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "diagnosis/diagnosis_plants.h"
#include "diagnosis/diagnosis_report.h"
#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

struct OmniCase {
  std::string label;
  std::string hidden;  // YAML for the plant's effects block
  std::vector<std::pair<std::string, std::map<std::string, double>>> expected;  // empty: nothing
  double tolerance = 0.15;  // relative, on every expected parameter
};

void PrintTo(const OmniCase& c, std::ostream* os) { *os << c.label; }

std::vector<OmniCase> OmniCases() {
  return {
      {"clean", "", {}},
      {"delay_20ms", "  time_delay: {delay: 0.02}\n", {{"time_delay", {{"delay", 0.02}}}}},
      {"delay_60ms", "  time_delay: {delay: 0.06}\n", {{"time_delay", {{"delay", 0.06}}}}},
      {"motor_lag_40ms", "  motor_lag: {time_constant: 0.04}\n", {{"motor_lag", {{"time_constant", 0.04}}}}},
      {"motor_lag_120ms", "  motor_lag: {time_constant: 0.12}\n", {{"motor_lag", {{"time_constant", 0.12}}}}},
      {"traction_1_2", "  traction_limit: {a_max: 1.2}\n", {{"traction_limit", {{"a_max", 1.2}}}}},
      {"traction_0_8", "  traction_limit: {a_max: 0.8}\n", {{"traction_limit", {{"a_max", 0.8}}}}},
      {"saturation_1_0", "  velocity_saturation: {v_max: 1.0}\n", {{"velocity_saturation", {{"v_max", 1.0}}}}},
      {"scale_1_1", "  velocity_scale: {scale: 1.1}\n", {{"velocity_scale", {{"scale", 1.1}}}}},
      {"scale_0_85", "  velocity_scale: {scale: 0.85}\n", {{"velocity_scale", {{"scale", 0.85}}}}},
      {"drift_0_3", "  rotation_drift: {rate: 0.3}\n", {{"rotation_drift", {{"rate", 0.3}}}}},
      {"drift_minus_0_8", "  rotation_drift: {rate: -0.8}\n", {{"rotation_drift", {{"rate", -0.8}}}}},
      {"turn_coupling_0_4", "  turn_coupling: {forward: 0.4}\n", {{"turn_coupling", {{"forward", 0.4}}}}},
      {"turn_coupling_sideways", "  turn_coupling: {sideways: -0.7}\n", {{"turn_coupling", {{"sideways", -0.7}}}}},
      {"cross_coupling_0_15", "  cross_coupling: {sideways_per_forward: 0.15}\n",
       {{"cross_coupling", {{"sideways_per_forward", 0.15}}}}},
      {"cross_coupling_back", "  cross_coupling: {forward_per_sideways: -0.2}\n",
       {{"cross_coupling", {{"forward_per_sideways", -0.2}}}}},
      {"saturation_0_7", "  velocity_saturation: {v_max: 0.7}\n", {{"velocity_saturation", {{"v_max", 0.7}}}}},
      // Look-alikes hidden together: a late command and a slow response. On 60 % of a
      // 30 s log they trade off: 46.7 ms and 61 ms (measured), the gap closed 85 % of
      // the way; hence 30 % on each.
      {"delay_and_lag", "  time_delay: {delay: 0.04}\n  motor_lag: {time_constant: 0.08}\n",
       {{"time_delay", {{"delay", 0.04}}}, {"motor_lag", {{"time_constant", 0.08}}}}, 0.3},
      {"traction_and_lag", "  traction_limit: {a_max: 1.2}\n  motor_lag: {time_constant: 0.06}\n",
       {{"traction_limit", {{"a_max", 1.2}}}, {"motor_lag", {{"time_constant", 0.06}}}}},
  };
}

class OmniDiagnosisCase : public ::testing::TestWithParam<OmniCase> {};

TEST_P(OmniDiagnosisCase, NamesWhatWasHiddenAndClosesTheGap) {
  const OmniCase& c = GetParam();
  const OmniModel nominal = testing::Omni4();
  const std::string yaml = "extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: hidden\n" +
                           (c.hidden.empty() ? "" : "effects:\n" + c.hidden);
  const OmniModel plant = LoadOmniModelFromString(yaml, "hidden.yaml");
  const std::vector<OmniLog> logs = {testing::RecordOmniPlant(plant, 30, 5)};
  DiagnosisOptions options;
  OmniModel repaired;
  const DiagnosisReport report = DiagnoseOmni(nominal, logs, options, &repaired);
  SCOPED_TRACE(FormatDiagnosisTable(report));
  if (std::getenv("TWINSIM_PRINT_DIAGNOSIS")) std::cout << FormatDiagnosisTable(report);

  ASSERT_EQ(report.effects.size(), c.expected.size());
  for (const auto& [name, parameters] : c.expected) {
    const auto it = std::find_if(report.effects.begin(), report.effects.end(),
                                 [&, &name = name](const DiagnosedEffect& e) { return e.name == name; });
    ASSERT_NE(it, report.effects.end()) << "expected " << name;
    EXPECT_EQ(it->joint, -1);
    for (const auto& [key, value] : parameters) {
      ASSERT_TRUE(it->parameters.count(key)) << name << " " << key;
      EXPECT_NEAR(it->parameters.at(key), value, c.tolerance * std::abs(value)) << name << " " << key;
    }
  }
  const double floor = DiagnoseOmni(plant, logs, testing::GapsOnly(options)).gap_before;
  testing::RecordDiagnosis(report, floor);  // for docs/diagnose.md's counts
  if (c.expected.empty()) {
    EXPECT_EQ(report.gap_after, report.gap_before);
  } else {
    EXPECT_GE((report.gap_before - report.gap_after) / (report.gap_before - floor), 0.7)
        << "nominal " << report.gap_before << ", repaired " << report.gap_after << ", plant " << floor;
  }
  // The camera's noise, estimated from the log alone, predicts the plant's own gap.
  EXPECT_NEAR(report.noise_floor, floor, 0.25 * floor);
  EXPECT_EQ(ListOmniEffects(repaired.effects).size(), c.expected.size());
  EXPECT_EQ(report.paths.size(), 3u);
  // Every horizon on the test rows: the repaired model is no worse than the given one
  // further ahead either (5 % of slack for the few rows of a 30 s log), and unchanged
  // where nothing was added.
  ASSERT_EQ(report.horizons.size(), 4u);
  for (const DiagnosisHorizon& h : report.horizons) {
    ASSERT_EQ(h.predictors.size(), 5u);
    EXPECT_EQ(h.predictors[1], "repaired model");
    EXPECT_EQ(h.predictors[4], "linear predictor");  // the seed's, trained on the fit rows
    EXPECT_GT(h.rows, 10) << h.label;
    if (c.expected.empty()) {
      EXPECT_EQ(h.gaps[1], h.gaps[0]) << h.label;
    } else {
      EXPECT_LE(h.gaps[1], 1.05 * h.gaps[0]) << h.label;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(HiddenEffects, OmniDiagnosisCase, ::testing::ValuesIn(OmniCases()),
                         [](const ::testing::TestParamInfo<OmniCase>& info) { return info.param.label; });

// A model identify wrote carries effects of the vocabulary (a delay beyond its frames,
// per-axis scales and lags, a coupling). A robot that changed since is named by a change
// of those numbers, refitted from the model's own (before, the model's effects were never
// candidates and a longer delay or a worn wheel went unexplained); the same robot
// unchanged names nothing. A robot that lags longer is named by a lag in series with the
// model's own (motor_lag's `series`, one number: grown per axis, three, it lost to the
// delay, its look-alike, on the robot of omni_foreign_diagnosis_test.cc), and a longer
// delay is not taken for it; one that lags less, which no lag in series makes, by its own
// lags scaled down. 30 s of the analytic robot at 30 fps each. The covariance
// identify wrote of the model's parameters is kept where nothing changed and left out of
// a repaired model, which it no longer describes.
TEST(OmniDiagnosis, NamesAChangeOfAnEffectTheModelAlreadyHas) {
  const std::string identified = "extends: " + testing::SourcePath("models/omni4.yaml") +
                                 "\nname: identified\neffects:\n"
                                 "  turn_coupling: {sideways: 0.3}\n";
  const std::string delay = "  time_delay: {delay: 0.03}\n";
  const std::string scales = "  velocity_scale: {forward: 0.8, sideways: 0.7, turn: 0.9}\n";
  const std::string lags = "  motor_lag: {forward: 0.08, sideways: 0.1, turn: 0.06}\n";
  const std::string covariance =
      "observer: {parameter_covariance: {parameters: [delay, forward.gain], matrix: [[4e-6, 0], [0, 1e-4]]}}\n";
  const OmniModel given = LoadOmniModelFromString(identified + delay + scales + lags + covariance, "given.yaml");
  struct Case {
    std::string plant_effects, name, key;
    double value;
  };
  const std::vector<Case> cases = {
      {delay + scales + lags, "", "", 0},
      {"  time_delay: {delay: 0.07}\n" + scales + lags, "time_delay", "delay", 0.07},
      {delay + "  velocity_scale: {scale: 0.8, forward: 0.8, sideways: 0.7, turn: 0.9}\n" + lags, "velocity_scale", "scale",
       0.8},
      {delay + scales + "  motor_lag: {forward: 0.08, sideways: 0.1, turn: 0.06, series: 0.15}\n", "motor_lag", "series",
       0.15},
      {delay + scales + "  motor_lag: {forward: 0.04, sideways: 0.05, turn: 0.03}\n", "motor_lag", "forward", 0.04},
  };
  for (const Case& c : cases) {
    const OmniModel plant = LoadOmniModelFromString(identified + c.plant_effects, "plant.yaml");
    OmniModel repaired;
    const DiagnosisReport report =
        DiagnoseOmni(given, {testing::RecordOmniPlant(plant, 30, 5)}, DiagnosisOptions{}, &repaired);
    SCOPED_TRACE(FormatDiagnosisTable(report));
    EXPECT_EQ(repaired.observer.parameter_covariance.empty(), !c.name.empty());
    if (c.name.empty()) {
      EXPECT_TRUE(report.effects.empty());
      for (const char* kept : {"time_delay", "velocity_scale", "turn_coupling", "motor_lag"}) {
        const std::string note = "the model's own " + std::string(kept) + " was kept: no change of its numbers passed the tests";
        EXPECT_NE(std::find(report.notes.begin(), report.notes.end(), note), report.notes.end()) << note;
      }
      continue;
    }
    ASSERT_EQ(report.effects.size(), 1u);
    EXPECT_EQ(report.effects[0].name, c.name);
    EXPECT_NEAR(report.effects[0].parameters.at(c.key), c.value, 0.1 * c.value);
    if (c.key == "series") {
      // A lag in series keeps the model's own lags: the repaired model holds both.
      EXPECT_EQ(repaired.effects.axis_lag, (std::array<double, 3>{0.08, 0.1, 0.06}));
      EXPECT_NEAR(repaired.effects.lag_series, 0.15, 0.015);
    }
    EXPECT_LT(report.gap_after, 0.5 * report.gap_before);
    EXPECT_NE(report.effects[0].evidence.find("(a change: the model had"), std::string::npos) << report.effects[0].evidence;
  }
}

TEST(OmniDiagnosis, SameLogsSameReportWhateverTheThreads) {
  OmniModel plant = testing::Omni4();
  plant.effects.motor_lag = 0.08;
  const std::vector<OmniLog> logs = {testing::RecordOmniPlant(plant, 20, 7)};
  DiagnosisOptions one, two;
  one.threads = 1;
  two.threads = 2;
  one.max_effects = two.max_effects = 1;
  EXPECT_EQ(FormatDiagnosisJson(DiagnoseOmni(testing::Omni4(), logs, one)),
            FormatDiagnosisJson(DiagnoseOmni(testing::Omni4(), logs, two)));
}

// The learned yardstick is the hybrid train --residual keeps (issue 63): both tracks
// trained on the fit rows, the one whose held-out rollouts come nearer kept, and the
// report says which. A robot played by ODE at 60 fps, seen as an SSL camera sees it,
// diagnosed with its own model file (whose analytic physics the ODE robot follows
// closely, not exactly): the yardstick is trained and finds nothing predictable. Until
// then a correction a few per cent worse than the physics on the test rows counted as
// not trained, and the report could not tell whether anything was predictable.
TEST(OmniDiagnosis, TheYardstickIsTheHybridTrainKeepsAndFindsNothingOnAWellModelledRobot) {
  const OmniModel plant = LoadOmniModel(testing::SourcePath("models/omni4_real_like.yaml"));
  const std::vector<OmniLog> logs = {testing::RecordOmniOpenWorld(plant, 30, 11, testing::OmniRecording{})};
  const DiagnosisReport report = DiagnoseOmni(plant, logs, {});
  SCOPED_TRACE(FormatDiagnosisTable(report));
  EXPECT_TRUE(report.effects.empty());
  ASSERT_TRUE(report.yardstick.available) << report.yardstick.learner;
  // The kept track is the one whose held-out rollouts came nearer (the tracker on a tie).
  const std::string& learner = report.yardstick.learner;
  const std::size_t at = learner.find("held-out 1 s rollouts ");
  ASSERT_NE(at, std::string::npos) << learner;
  double observer = 0, tracker = 0;
  ASSERT_EQ(std::sscanf(learner.c_str() + at, "held-out 1 s rollouts %lf mm from the observer's state, %lf", &observer,
                        &tracker),
            2)
      << learner;
  EXPECT_NE(learner.find(observer < tracker ? "carried by its observer" : "carried by its tracker"), std::string::npos)
      << learner;
  // It learned nothing: within 5 % of the physics (measured 2.3 % worse).
  EXPECT_LE(report.yardstick.nominal, 1.05 * report.gap_before);
  for (const ChannelAdequacy& a : report.adequacy) EXPECT_FALSE(a.learned_significant) << a.channel;
  const std::string verdict = DiagnosisVerdict(report);
  EXPECT_NE(verdict.find("a learned residual finds nothing predictable"), std::string::npos) << verdict;
}

// omni4 wandering by 0.05, 0.05 m/s and 0.3 rad/s over 0.2 s, drawn by the simulation
// (driving_noise.simulated, as identify writes it).
OmniModel WanderingOmni4() {
  OmniModel m = testing::Omni4();
  m.driving_noise.sd = {0.05, 0.05, 0.3};
  m.driving_noise.correlation_time = 0.2;
  m.driving_noise.simulated = true;
  return m;
}

// A robot that wanders (driving noise the wheels do not see, drawn by the simulation)
// diagnosed with its own model: what is left half a second ahead is the wander, which
// no model predicts. The floor draws it where the model says its robot wanders
// (driving_noise.simulated, as identify writes it) and so predicts the robot's own gap;
// the same model without that flag (its noise then only tunes the observer) gets the
// camera's floor, far below the gap, and its channels read unexplained.
TEST(OmniDiagnosis, TheNoiseFloorCountsTheWanderTheModelSaysItsRobotHas) {
  const OmniModel wandering = WanderingOmni4();
  const std::vector<OmniLog> logs = {testing::RecordOmniPlant(wandering, 30, 5)};
  const DiagnosisReport report = DiagnoseOmni(wandering, logs, testing::GapsOnly());
  // On the fit rows, half the log: the four test blocks alone gave 22 to 37 mm over seeds
  // 5 to 10 where the fit rows gave 28 to 31 and the drawn floor 30 to 33 (measured; the
  // floor is held at the fit rows' error where the draw exceeds it: 31.1 and 27.6 mm
  // here, within the two's scatter, so nothing is said of it).
  EXPECT_NEAR(report.noise_floor, report.fit_gap_before, 0.15 * report.fit_gap_before);
  for (const std::string& n : report.notes) EXPECT_EQ(n.find("wanders less than the noise says"), std::string::npos) << n;
  OmniModel observer_only = wandering;
  observer_only.driving_noise.simulated = false;
  const DiagnosisReport camera = DiagnoseOmni(observer_only, logs, testing::GapsOnly());
  EXPECT_EQ(camera.fit_gap_before, report.fit_gap_before);  // the same observer: only the floor differs
  EXPECT_LT(camera.noise_floor, 0.3 * report.noise_floor);   // measured 5.8 against 27.6 mm
}

// The same robot diagnosed with a model that says it wanders three times as much (a
// driving noise fitted wide, as identify's was on the real Robotino: its 0.5 s intervals
// held 99 % of the measured poses in their 90 % regions). The wander drawn from that
// noise would put the floor far above the model's own error on these logs, which a
// perfect model cannot exceed: the floor is held at that error and a note says the noise
// is wider than the robot wanders. Before, the floor stood at 3.1 times the fit rows'
// error (measured 88.9 against 28.4 mm) and no channel could read unexplained.
TEST(OmniDiagnosis, AFloorAboveTheModelsOwnErrorIsHeldAtItAndSaid) {
  const OmniModel wandering = WanderingOmni4();
  const std::vector<OmniLog> logs = {testing::RecordOmniPlant(wandering, 30, 5)};
  OmniModel wide = wandering;
  wide.driving_noise.sd = {0.15, 0.15, 0.9};
  const DiagnosisReport report = DiagnoseOmni(wide, logs, testing::GapsOnly());
  EXPECT_LE(report.noise_floor, report.fit_gap_before * (1 + 1e-12));
  EXPECT_GT(report.noise_floor, 0.7 * report.fit_gap_before);
  const auto said = std::find_if(report.notes.begin(), report.notes.end(), [](const std::string& n) {
    return n.find("this robot wanders less than the noise says") != std::string::npos;
  });
  ASSERT_NE(said, report.notes.end()) << ::testing::PrintToString(report.notes);
  double drawn = 0, own = 0;
  ASSERT_EQ(std::sscanf(said->c_str(), "the model's driving noise draws its robot wandering by %lf mm over the %*d frames "
                        "predicted, more than the model's own error on the fit rows (%lf",
                        &drawn, &own),
            2)
      << *said;
  EXPECT_NEAR(own, 1000 * report.fit_gap_before, 0.01);
  EXPECT_GT(drawn, 2 * own);
  // The verdict says it, and report.json carries both numbers.
  EXPECT_NEAR(1000 * report.drawn_floor, drawn, 0.01);
  EXPECT_NEAR(1000 * report.own_fit_error, own, 0.01);
  const std::string verdict = DiagnosisVerdict(report);
  EXPECT_NE(verdict.find("draws more wander than this robot shows"), std::string::npos) << verdict;
  EXPECT_NE(FormatDiagnosisJson(report).find("\"drawn_noise_floor\""), std::string::npos);
}

TEST(OmniDiagnosis, RefusesBadInput) {
  const OmniModel nominal = testing::Omni4();
  const OmniLog log = testing::RecordOmniPlant(nominal, 1.5, 1);
  EXPECT_THROW(DiagnoseOmni(nominal, {log}, {}), InputError);  // 1.5 s: too little to hold out
  DiagnosisOptions learned;
  learned.backend = "learned";
  const OmniLog longer = testing::RecordOmniPlant(nominal, 20, 1);
  EXPECT_THROW(DiagnoseOmni(nominal, {longer}, learned), InputError);
  DiagnosisOptions bad;
  bad.held_out = 1.5;
  EXPECT_THROW(DiagnoseOmni(nominal, {longer}, bad), InputError);
}

TEST(OmniEffects, SetAndListRoundTripEveryEffect) {
  OmniEffects e;
  for (const std::string& name : OmniEffectNames()) {
    std::map<std::string, double> p;
    for (const std::string& key : OmniEffectParameters(name)) p[key] = key == "scale" ? 1.2 : key == "field_frame" ? 1 : 0.3;
    SetOmniEffect(name, p, &e);
  }
  const auto listed = ListOmniEffects(e);
  ASSERT_EQ(listed.size(), OmniEffectNames().size());
  OmniEffects again;
  for (const auto& [name, p] : listed) SetOmniEffect(name, p, &again);
  EXPECT_EQ(ListOmniEffects(again), listed);
  try {
    SetOmniEffect("traction_limit", {{"a_max", -1}}, &e);
    FAIL();
  } catch (const InputError& ex) {
    EXPECT_NE(std::string(ex.what()).find("a_max"), std::string::npos) << ex.what();
  }
  EXPECT_THROW(SetOmniEffect("wheel_wobble", {}, &e), InputError);
  EXPECT_THROW(SetOmniEffect("motor_lag", {{"tau", 0.1}}, &e), InputError);
}

}  // namespace
}  // namespace twinsim
