// The omni model writer: any model written and loaded back is the same model, bit for bit.
#include "robots/omni/omni_model_yaml_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/math_constants.h"
#include "test_util.h"

namespace twinsim {
namespace {

void ExpectSamePid(const PidGains& a, const PidGains& b) {
  EXPECT_EQ(a.AsVector(), b.AsVector());
}

// Every field with ==: the numbers must come back as the same doubles.
void ExpectSameModel(const OmniModel& a, const OmniModel& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.fitted_on, b.fitted_on);
  EXPECT_EQ(a.chassis_mass, b.chassis_mass);
  EXPECT_EQ(a.chassis_radius, b.chassis_radius);
  EXPECT_EQ(a.chassis_height, b.chassis_height);
  EXPECT_EQ(a.chassis_inertia_z, b.chassis_inertia_z);
  EXPECT_EQ(a.com_height, b.com_height);
  EXPECT_EQ(a.ground_clearance, b.ground_clearance);
  EXPECT_EQ(a.wheel_angles, b.wheel_angles);
  EXPECT_EQ(a.wheel_distance, b.wheel_distance);
  EXPECT_EQ(a.wheel_radius, b.wheel_radius);
  EXPECT_EQ(a.wheel_width, b.wheel_width);
  EXPECT_EQ(a.wheel_mass, b.wheel_mass);
  EXPECT_EQ(a.wheel_friction, b.wheel_friction);
  EXPECT_EQ(a.roller_friction, b.roller_friction);
  EXPECT_EQ(a.bearing_damping, b.bearing_damping);
  EXPECT_EQ(a.motor_stall_torque, b.motor_stall_torque);
  EXPECT_EQ(a.motor_no_load_speed, b.motor_no_load_speed);
  EXPECT_EQ(a.encoder_counts_per_rev, b.encoder_counts_per_rev);
  EXPECT_EQ(a.controller.rate_hz, b.controller.rate_hz);
  ExpectSamePid(a.controller.forward, b.controller.forward);
  ExpectSamePid(a.controller.sideways, b.controller.sideways);
  ExpectSamePid(a.controller.rotation, b.controller.rotation);
  EXPECT_EQ(a.command_delay_frames, b.command_delay_frames);
  EXPECT_EQ(a.vision_delay_frames, b.vision_delay_frames);
  EXPECT_EQ(a.effects.time_delay, b.effects.time_delay);
  EXPECT_EQ(a.effects.v_max, b.effects.v_max);
  EXPECT_EQ(a.effects.w_max, b.effects.w_max);
  EXPECT_EQ(a.effects.motor_lag, b.effects.motor_lag);
  EXPECT_EQ(a.effects.axis_lag, b.effects.axis_lag);
  EXPECT_EQ(a.effects.lag_braking, b.effects.lag_braking);
  EXPECT_EQ(a.effects.lag_field_frame, b.effects.lag_field_frame);
  EXPECT_EQ(a.effects.a_max, b.effects.a_max);
  EXPECT_EQ(a.effects.velocity_scale, b.effects.velocity_scale);
  EXPECT_EQ(a.effects.rotation_drift, b.effects.rotation_drift);
  EXPECT_EQ(a.vision_noise_xy, b.vision_noise_xy);
  EXPECT_EQ(a.vision_noise_theta, b.vision_noise_theta);
  EXPECT_EQ(a.vision_drop_probability, b.vision_drop_probability);
  // Derived by Finalize() from the same inputs.
  EXPECT_EQ(a.total_mass, b.total_mass);
  EXPECT_EQ(a.total_inertia_z, b.total_inertia_z);
  EXPECT_EQ(a.com_offset, b.com_offset);
  EXPECT_EQ(a.wheel_spin_inertia, b.wheel_spin_inertia);
  EXPECT_EQ(a.wheel_inertia_diametral, b.wheel_inertia_diametral);
  EXPECT_EQ(a.geometry, b.geometry);
  EXPECT_EQ(a.wheel_load, b.wheel_load);
}

OmniModel RoundTrip(const OmniModel& m) { return LoadOmniModelFromString(FormatOmniModelYaml(m), "again.yaml"); }

// The message a model of omni4 with `yaml` added (as bad.yaml, from its line 3) is
// refused with; "loaded" where it loads.
std::string Refused(const std::string& yaml) {
  try {
    LoadOmniModelFromString("extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: n\n" + yaml, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "loaded";
}

TEST(OmniModelYamlWriter, ShippedModelsRoundTripBitForBit) {
  for (const char* rel : {"models/omni4.yaml", "models/omni3.yaml", "models/omni4_plant.yaml"}) {
    SCOPED_TRACE(rel);
    const OmniModel m = LoadOmniModel(testing::SourcePath(rel));
    const std::string text = FormatOmniModelYaml(m);
    EXPECT_EQ(text.find("extends:"), std::string::npos) << text;
    ExpectSameModel(m, LoadOmniModelFromString(text, "again.yaml"));
    // The text is a fixed point.
    EXPECT_EQ(FormatOmniModelYaml(RoundTrip(m)), text);
  }
  // The plant's effects in the reader's syntax, in docs/models.md's order.
  const std::string plant = FormatOmniModelYaml(LoadOmniModel(testing::SourcePath("models/omni4_plant.yaml")));
  const std::size_t delay = plant.find("effects:\n  time_delay: {delay: 0.02}   ");
  EXPECT_NE(delay, std::string::npos) << plant;
  EXPECT_GT(plant.find("\n  velocity_saturation: {v_max: 1.7, w_max: 5}"), delay) << plant;
  EXPECT_NE(plant.find("angles_deg: [57, 135, 225, 303]"), std::string::npos) << plant;
}

TEST(OmniModelYamlWriter, AwkwardNumbersAndGivenChassisInertiaRoundTrip) {
  OmniModel m = testing::Omni4();
  m.name = "odd: name";
  m.chassis_inertia_z = 0.1 / 3;  // kg m^2, written as given, not the derived total
  m.chassis_mass = 2.3 + 1e-13;   // kg
  m.wheel_angles = {0.1, 2 * kPi / 3, kPi, 5.0};  // rad, not from degrees
  m.controller.rotation.kp = 1.0 / 7;
  m.vision_noise_xy = 1.2345678901234567e-5;  // m
  m.command_delay_frames = 0;
  m.Finalize();
  const std::string text = FormatOmniModelYaml(m);
  EXPECT_NE(text.find("inertia_z: 0.03333333333333333 "), std::string::npos) << text;
  const OmniModel back = LoadOmniModelFromString(text, "odd.yaml");
  // Angles in rad need not be exact in degrees; allow one ulp, and check the rest with them.
  ASSERT_EQ(back.wheel_angles.size(), m.wheel_angles.size());
  for (std::size_t i = 0; i < m.wheel_angles.size(); ++i) EXPECT_NEAR(back.wheel_angles[i], m.wheel_angles[i], 1e-15);
  m.wheel_angles = back.wheel_angles;
  m.Finalize();
  ExpectSameModel(m, back);
}

TEST(OmniModelYamlWriter, TheFlatFrontKickerAndDribblerRoundTripAndAreLeftOutAtTheirDefaults) {
  OmniModel m = testing::Omni4();
  const std::string plain = FormatOmniModelYaml(m);
  EXPECT_EQ(plain.find("front_distance"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("kicker"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("dribbler"), std::string::npos) << plain;
  m.front_distance = 0.0701;  // m
  m.kicker_max_speed = 8.25;  // m/s
  m.dribbler_max_force = 0.7;  // N
  const OmniModel back = LoadOmniModelFromString(FormatOmniModelYaml(m), "ball.yaml");
  EXPECT_EQ(back.front_distance, m.front_distance);
  EXPECT_EQ(back.kicker_max_speed, m.kicker_max_speed);
  EXPECT_EQ(back.dribbler_max_force, m.dribbler_max_force);
  ExpectSameModel(m, back);
}

// The driving noise and the observer's noise: left out at their defaults, written and
// read back bit for bit otherwise; out-of-range values are the file's errors.
TEST(OmniModelYamlWriter, DrivingNoiseAndObserverRoundTripAndAreLeftOutAtTheirDefaults) {
  OmniModel m = testing::Omni4();
  const std::string plain = FormatOmniModelYaml(m);
  EXPECT_EQ(plain.find("driving_noise:"), std::string::npos);
  EXPECT_EQ(plain.find("observer:"), std::string::npos);
  m.driving_noise.sd = {0.123, 0.1 / 3, 1.7};
  m.driving_noise.correlation_time = 0.21;
  m.observer.process_noise = {0.05, 0.07, 0.9};
  m.observer.measurement_noise_xy = 0.0015;
  m.observer.measurement_noise_theta = 0.02;
  const OmniModel back = RoundTrip(m);
  EXPECT_EQ(back.driving_noise.sd, m.driving_noise.sd);
  EXPECT_EQ(back.driving_noise.correlation_time, m.driving_noise.correlation_time);
  EXPECT_EQ(back.observer.process_noise, m.observer.process_noise);
  EXPECT_EQ(back.observer.measurement_noise_xy, 0.0015);
  EXPECT_EQ(back.ObserverNoiseTheta(), 0.02);
  EXPECT_EQ(FormatOmniModelYaml(back), FormatOmniModelYaml(m));
  const std::string base = "extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: n\n";
  try {
    LoadOmniModelFromString(base + "driving_noise: {forward: -0.1, correlation_time: 0}\n", "bad.yaml");
    ADD_FAILURE() << "a negative spread loads";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad.yaml:3:"), std::string::npos) << what;
    EXPECT_NE(what.find("forward"), std::string::npos) << what;
    EXPECT_NE(what.find("correlation_time"), std::string::npos) << what;
  }
  EXPECT_THROW(LoadOmniModelFromString(base + "observer: {process_noise: {sideways: 0}}\n", "bad.yaml"), InputError);
  EXPECT_THROW(LoadOmniModelFromString(base + "observer: {slip: 1}\n", "bad.yaml"), InputError);
}

// The noise's drift, a slow slip beside it: written only where it has a spread, round
// trips bit for bit, and a drift with a time of none or a negative spread is refused
// where it is written.
TEST(OmniModelYamlWriter, TheNoisesDriftRoundTripsAndIsChecked) {
  OmniModel m = testing::Omni4();
  m.driving_noise.drift.correlation_time = 7;  // no spread: no drift, not written
  EXPECT_EQ(FormatOmniModelYaml(m).find("drift"), std::string::npos);
  m.driving_noise.drift.sd = {0.0123, 0, 0.1 / 3};
  const std::string text = FormatOmniModelYaml(m);
  EXPECT_NE(text.find("drift: {"), std::string::npos) << text;
  const OmniModel back = RoundTrip(m);
  EXPECT_EQ(back.driving_noise.drift.sd, m.driving_noise.drift.sd);
  EXPECT_EQ(back.driving_noise.drift.correlation_time, 7);
  EXPECT_EQ(FormatOmniModelYaml(back), text);
  const std::string base = "extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: n\n";
  try {
    LoadOmniModelFromString(base + "driving_noise:\n  drift: {turn: -0.1, correlation_time: 0}\n", "bad.yaml");
    ADD_FAILURE() << "a drift with a negative spread loads";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad.yaml:4:"), std::string::npos) << what;
    EXPECT_NE(what.find("turn"), std::string::npos) << what;
    EXPECT_NE(what.find("correlation_time"), std::string::npos) << what;
  }
  EXPECT_THROW(LoadOmniModelFromString(base + "driving_noise: {drift: {wander: 1}}\n", "bad.yaml"), InputError);
}

// Issue 64: the intervals' safeguard, a scale of the predicted covariance per horizon,
// round-trips, is interpolated in log(frames) between horizons and held beyond them, and
// a list out of order or out of range is refused where it is written.
TEST(OmniModelYamlWriter, TheIntervalsSafeguardRoundTripsInterpolatesAndIsChecked) {
  OmniModel m = testing::Omni4();
  EXPECT_EQ(m.observer.IntervalScaleAt(10), (std::array<double, 2>{1, 1}));
  m.observer.interval_scale = {{4, 2.0, 0.8}, {16, 0.5, 1 / 3.0}, {63, 0.7, 1.25}};
  const std::string text = FormatOmniModelYaml(m);
  EXPECT_NE(text.find("interval_scale:"), std::string::npos) << text;
  const OmniModel back = RoundTrip(m);
  ASSERT_EQ(back.observer.interval_scale.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.observer.interval_scale[i].frames, m.observer.interval_scale[i].frames);
    EXPECT_EQ(back.observer.interval_scale[i].position, m.observer.interval_scale[i].position);
    EXPECT_EQ(back.observer.interval_scale[i].heading, m.observer.interval_scale[i].heading);
  }
  EXPECT_EQ(FormatOmniModelYaml(back), text);
  // 8 frames lie halfway between 4 and 16 in log(frames): the geometric mean.
  EXPECT_NEAR(back.observer.IntervalScaleAt(8)[0], 1.0, 1e-12);
  EXPECT_NEAR(back.observer.IntervalScaleAt(8)[1], std::sqrt(0.8 / 3), 1e-12);
  EXPECT_EQ(back.observer.IntervalScaleAt(1)[0], 2.0);
  EXPECT_EQ(back.observer.IntervalScaleAt(200)[1], 1.25);

  const std::string order = Refused(
      "observer:\n  interval_scale:\n    - {frames: 16, position: 1, heading: 1}\n    - {frames: 4, position: 1, "
      "heading: 1}\n");
  EXPECT_NE(order.find("bad.yaml:6:"), std::string::npos) << order;
  EXPECT_NE(order.find("increase"), std::string::npos) << order;
  const std::string range = Refused("observer: {interval_scale: [{frames: 4, position: 0, heading: 1}]}\n");
  EXPECT_NE(range.find("bad.yaml:3:"), std::string::npos) << range;
  EXPECT_NE(range.find("position"), std::string::npos) << range;
  EXPECT_NE(Refused("observer: {interval_scale: 2}\n").find("a list of"), std::string::npos);
  EXPECT_NE(Refused("observer: {interval_scale: [{frames: 4, position: 1}]}\n").find("heading"), std::string::npos);
}

// Issue 64: a scale that grows with the distance from the fit's inputs round-trips with
// those inputs, grows as s (1 + g d), interpolates its growth linearly in log(k), and a
// growth without seen inputs, or inputs of the wrong length, are refused.
TEST(OmniModelYamlWriter, AGrowthOutOfTheFitsReachRoundTripsWithItsSeenInputs) {
  OmniModel m = testing::Omni4();
  m.observer.interval_scale = {{4, 2.0, 0.8, 3.0, 0.0}, {16, 0.5, 1.0, 1.0, 2.0}};
  Eigen::VectorXd u = Eigen::VectorXd::Zero(8);
  u << 1, 2, 3, 4, 0.5, 1.5, 2.5, 3.5;
  m.observer.seen_inputs = MakeSeenInputs({u, 2 * u, -u});
  const std::string text = FormatOmniModelYaml(m);
  EXPECT_NE(text.find("position_growth: 3"), std::string::npos) << text;
  EXPECT_NE(text.find("seen_inputs:"), std::string::npos) << text;
  const OmniModel back = RoundTrip(m);
  ASSERT_EQ(back.observer.interval_scale.size(), 2u);
  EXPECT_EQ(back.observer.interval_scale[0].position_growth, 3.0);
  EXPECT_EQ(back.observer.interval_scale[1].heading_growth, 2.0);
  ASSERT_EQ(back.observer.seen_inputs.points.size(), 3u);
  EXPECT_EQ(back.observer.seen_inputs.scale, m.observer.seen_inputs.scale);
  EXPECT_EQ(back.observer.seen_inputs.points[1], m.observer.seen_inputs.points[1]);
  EXPECT_EQ(FormatOmniModelYaml(back), text);
  EXPECT_NEAR(back.observer.IntervalScaleAt(4, 0.5)[0], 2.0 * (1 + 3.0 * 0.5), 1e-12);
  EXPECT_NEAR(back.observer.IntervalScaleAt(4, 0.5)[1], 0.8, 1e-12);
  EXPECT_NEAR(back.observer.IntervalScaleAt(8, 1.0)[0], 1.0 * (1 + 2.0), 1e-12);  // halfway: growth 2
  EXPECT_NEAR(back.observer.IntervalScaleAt(8, 0.0)[0], 1.0, 1e-12);

  EXPECT_NE(Refused("observer: {interval_scale: [{frames: 4, position: 1, heading: 1, position_growth: 2}]}\n")
                .find("seen_inputs"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {seen_inputs: {scale: 1, points: [[1, 2, 3]]}}\n").find("8 finite wheel speeds"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {seen_inputs: {scale: 1, points: []}}\n").find("bad.yaml:3:"), std::string::npos);
  EXPECT_NE(Refused("observer: {seen_inputs: {scale: 1, points: [[1, x, 3]]}}\n").find("bad.yaml:3:"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {interval_scale: [{frames: 4, position: 1, heading: 1, heading_growth: -1}]}\n")
                .find("heading_growth"),
            std::string::npos);
}

// Issue 64: identify's covariance of the response's parameters round-trips bit for bit,
// and a malformed one is refused where it is written.
TEST(OmniModelYamlWriter, TheParametersCovarianceRoundTripsAndAMalformedOneIsRefused) {
  OmniModel m = testing::Omni4();
  Eigen::MatrixXd c(2, 2);
  c << 3.4778147306033741e-05, 9.4025384716445016e-08, 9.4025384716445016e-08, 9.8787006134324031e-06;
  m.observer.parameter_covariance = {{"forward.gain", "delay"}, c};
  const std::string text = FormatOmniModelYaml(m);
  EXPECT_NE(text.find("parameters: [forward.gain, delay]"), std::string::npos) << text;
  const OmniModel back = RoundTrip(m);
  EXPECT_EQ(back.observer.parameter_covariance.parameters, m.observer.parameter_covariance.parameters);
  EXPECT_EQ(back.observer.parameter_covariance.matrix, c);
  EXPECT_EQ(FormatOmniModelYaml(back), text);

  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [delay], matrix: [[1e-6, 0]]}}\n").find("1 numbers"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [a, b], matrix: [[1, 0.5], [0.4, 1]]}}\n")
                .find("symmetric"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [a], matrix: [[-1]]}}\n").find("positive diagonal"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [a, a], matrix: [[1, 0], [0, 1]]}}\n")
                .find("listed twice"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [a], matrix: [[x]]}}\n").find("bad.yaml:3:"),
            std::string::npos);
  EXPECT_NE(Refused("observer: {parameter_covariance: {parameters: [], matrix: []}}\n").find("bad.yaml:3:"),
            std::string::npos);
}

// Issue 63: a fitted model names the engine it was fitted on, and commands replay it
// there unless told otherwise, saying so when told.
TEST(OmniModelYamlWriter, TheEngineAModelWasFittedOnRoundTripsAndChoosesTheReplaysEngine) {
  OmniModel m = testing::Omni4();
  EXPECT_EQ(FormatOmniModelYaml(m).find("fitted_on"), std::string::npos);
  EXPECT_EQ(ReplayEngineFor(m, "", "ode"), "ode");
  m.fitted_on = "analytic";
  const OmniModel back = RoundTrip(m);
  EXPECT_EQ(back.fitted_on, "analytic");
  EXPECT_EQ(FormatOmniModelYaml(back), FormatOmniModelYaml(m));
  std::string note = "stale";
  EXPECT_EQ(ReplayEngineFor(back, "", "ode", &note), "analytic");
  EXPECT_EQ(note, "");
  EXPECT_EQ(ReplayEngineFor(back, "analytic", "ode", &note), "analytic");
  EXPECT_EQ(note, "");
  EXPECT_EQ(ReplayEngineFor(back, "bullet", "ode", &note), "bullet");
  EXPECT_NE(note.find("was fitted on the analytic engine (fitted_on); replaying it on bullet as asked"),
            std::string::npos) << note;
  EXPECT_EQ(ReplayEngineFor(back, "learned", "ode", &note), "learned");
  EXPECT_EQ(note, "");  // a learned backend is not an engine of the model's physics
  const std::string base = "extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: n\n";
  try {
    LoadOmniModelFromString(base + "fitted_on: mujoco\n", "bad.yaml");
    ADD_FAILURE() << "an unknown engine loads";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:3:"), std::string::npos) << e.what();
  }
}

TEST(OmniModelYamlWriter, EachEffectAloneRoundTripsAndNoneWritesNoBlock) {
  const OmniModel base = testing::Omni4();
  EXPECT_EQ(FormatOmniModelYaml(base).find("effects:"), std::string::npos);
  struct Case {
    const char* line;
    void (*set)(OmniEffects*);
  };
  const Case cases[] = {
      {"  time_delay: {delay: 0.0123}", [](OmniEffects* e) { e->time_delay = 0.0123; }},
      {"  velocity_saturation: {v_max: 1.7}", [](OmniEffects* e) { e->v_max = 1.7; }},
      {"  velocity_saturation: {w_max: 0.3333333333333333}", [](OmniEffects* e) { e->w_max = 1.0 / 3; }},
      {"  motor_lag: {time_constant: 0.08}", [](OmniEffects* e) { e->motor_lag = 0.08; }},
      {"  motor_lag: {braking: 0.4, field_frame: 1, forward: 0.11, turn: 0.07}", [](OmniEffects* e) {
         e->axis_lag = {0.11, 0, 0.07};
         e->lag_braking = 0.4;
         e->lag_field_frame = true;
       }},
      {"  traction_limit: {a_max: 2.5}", [](OmniEffects* e) { e->a_max = 2.5; }},
      {"  velocity_scale: {scale: 0.9}", [](OmniEffects* e) { e->velocity_scale = 0.9; }},
      {"  rotation_drift: {rate: -0.2}", [](OmniEffects* e) { e->rotation_drift = -0.2; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.line);
    OmniModel m = base;
    c.set(&m.effects);
    ASSERT_EQ(m.effects.Active().size(), 1u);
    const std::string text = FormatOmniModelYaml(m);
    const std::string block = text.substr(text.find("effects:\n"));
    EXPECT_EQ(block.rfind(std::string("effects:\n") + c.line, 0), 0u) << block;
    EXPECT_EQ(std::count(block.begin(), block.end(), '\n'), 2) << block;  // the effect alone
    const OmniModel back = RoundTrip(m);
    EXPECT_EQ(back.effects.Active(), m.effects.Active());
    ExpectSameModel(m, back);
  }
}

TEST(OmniModelYamlWriter, WritesAtomicallyWithCommentHeader) {
  const std::string dir = testing::TempDir("omni_yaml_writer");
  const std::string path = dir + "/sub/omni4_copy.yaml";
  const OmniModel m = LoadOmniModel(testing::SourcePath("models/omni4_plant.yaml"));
  WriteOmniModelYaml(path, m, "diagnosed from run1.csv\nby twinsim diagnose");
  EXPECT_EQ(testing::ReadText(path).rfind("# diagnosed from run1.csv\n# by twinsim diagnose\nrobot: omni\nname: omni4_plant\n", 0),
            0u);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir + "/sub")) {
    EXPECT_EQ(entry.path().filename(), "omni4_copy.yaml");  // no temporary left behind
    ++files;
  }
  EXPECT_EQ(files, 1);
  ExpectSameModel(m, LoadOmniModel(path));
  // A folder that cannot be made (a file stands in its place).
  EXPECT_THROW(WriteOmniModelYaml(path + "/nested.yaml", m), InputError);
}

}  // namespace
}  // namespace twinsim
