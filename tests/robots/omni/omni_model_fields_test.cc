// The omni model file's table of numbers (robots/omni/omni_model_fields.h): every number
// it lists is read by the reader at its key with its check and written back by the
// writer, so a key, a range or a unit lives in one place.
#include "robots/omni/omni_model_fields.h"

#include <gtest/gtest.h>

#include <set>

#include "core/error.h"
#include "io/yaml_overrides.h"
#include "robots/omni/omni_model_yaml_writer.h"

namespace twinsim {
namespace {

// A model with every section written: wheels with strengths, a centre of mass, a flat
// front, kicker and dribbler off their defaults, driving noise with its growths and
// drift, an observer of its own.
OmniModel EverySection() {
  return LoadOmniModelFromString(R"(robot: omni
name: every_section
chassis: {mass: 2.1, radius: 0.09, height: 0.14, inertia_z: 0.01, com_height: 0.05, com: [0.003, -0.002], ground_clearance: 0.004, front_distance: 0.07}
wheels: {angles_deg: [30, 150, 225, 315], distance: 0.08, radius: 0.027, width: 0.02, mass: 0.04, friction: 0.9, roller_friction: 0.3, bearing_damping: 0.001}
motor: {stall_torque: 0.5, no_load_speed: 300, encoder_counts_per_rev: 2048, strength: [1, 0.9, 1, 0.95]}
kicker: {max_speed: 6}
dribbler: {max_force: 2, full_speed: 12000}
controller:
  rate_hz: 500
  forward: {kp: 10, ki: 1, kd: 0.1, integral_limit: 5, output_limit: 20, slew_rate: 3}
  sideways: {kp: 11, ki: 1.5, kd: 0.2, integral_limit: 6, output_limit: 21, slew_rate: 2.5}
  rotation: {kp: 1, ki: 0.1, kd: 0.01, integral_limit: 0.5, output_limit: 2, slew_rate: 40}
delay: {command_frames: 2, vision_frames: 1}
vision: {noise_xy: 0.002, noise_theta: 0.01, drop_probability: 0.05, repeat_probability: 0.02, time_jitter: 0.001}
driving_noise: {forward: 0.03, sideways: 0.02, turn: 0.2, correlation_time: 0.3, per_speed: 1.5, per_acceleration: 0.2, per_turn_rate: 0.1, drift: {forward: 0.01, sideways: 0.005, turn: 0.02, correlation_time: 20}}
observer:
  process_noise: {forward: 0.2, sideways: 0.3, turn: 1.1}
  measurement_noise: {xy: 0.0015, theta: 0.006}
)",
                                 "every_section.yaml");
}

TEST(OmniModelFields, EveryNumberIsReadAtItsKeyAndWrittenBack) {
  const OmniModel base = EverySection();
  // Each number moved off its value (by 1 % or one frame) within its own check: the
  // writer must write it and the reader read it back, or the value comes back unmoved.
  OmniModel moved = base;
  int numbers = 0;
  for (const OmniModelField& f : OmniModelFields()) {
    if (f.custom) continue;
    ++numbers;
    const double v = f.get(base);
    const double w = f.integer ? v + 1 : v * 1.01;
    ASSERT_NE(w, v) << f.path() << ": the model above must set it";
    ASSERT_EQ(f.check(w), "") << f.path();
    f.set(&moved, w);
  }
  EXPECT_EQ(numbers, 62);  // every number of the file outside effects
  const OmniModel back = LoadOmniModelFromString(FormatOmniModelYaml(moved), "moved.yaml");
  for (const OmniModelField& f : OmniModelFields()) {
    if (f.custom) continue;
    EXPECT_EQ(f.get(back), f.get(moved)) << f.path();
    EXPECT_NE(f.get(back), f.get(base)) << f.path();
  }
}

TEST(OmniModelFields, EveryNumberIsCheckedWhereItIsRead) {
  const YAML::Node root = YAML::Load(FormatOmniModelYaml(EverySection()));
  for (const OmniModelField& f : OmniModelFields()) {
    if (f.custom) continue;
    ASSERT_NE(f.check(1e12), "") << f.path() << ": every number has an upper bound";
    const YAML::Node bad = ApplyYamlOverrides(root, {{f.path(), YAML::Node(1e12)}}, "bad.yaml");
    try {
      LoadOmniModelFromString(YAML::Dump(bad), "bad.yaml");
      ADD_FAILURE() << f.path() << " = 1e12 was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'" + f.key + "' in '" + f.section + "'"), std::string::npos)
          << f.path() << ": " << e.what();
    }
  }
}

TEST(OmniModelFields, EachPathIsListedOnceAndFound) {
  std::set<std::string> paths;
  for (const OmniModelField& f : OmniModelFields()) {
    EXPECT_TRUE(paths.insert(f.path()).second) << f.path() << " twice";
    EXPECT_EQ(&OmniModelFieldAt(f.path()), &f);
    if (!f.custom) {
      EXPECT_TRUE(f.get && f.set) << f.path();
    }
  }
  EXPECT_EQ(OmniModelFieldsOf("controller.rotation").size(), 6u);
  EXPECT_EQ(OmniModelFieldAt("controller.rotation.slew_rate").unit, "rad/s^2");
  EXPECT_THROW(OmniModelFieldAt("chassis.weight"), std::logic_error);
}

}  // namespace
}  // namespace twinsim
