#include "robots/omni/omni_model.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

const char* kGood = R"(robot: omni
name: tiny
chassis: {mass: 2.3, radius: 0.089, height: 0.14, com_height: 0.045}
wheels:
  angles_deg: [60, 180, 300]
  radius: 0.027
)";

std::string OmniModelErrorOf(const std::string& yaml) {
  try {
    LoadOmniModelFromString(yaml, "m.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(OmniModel, LoadsInlineModelWithDefaults) {
  OmniModel m = LoadOmniModelFromString(kGood, "m.yaml");
  EXPECT_EQ(m.name, "tiny");
  EXPECT_EQ(m.num_wheels(), 3);
  EXPECT_NEAR(m.total_mass, 2.3 + 3 * 0.05, 1e-12);
  // Static loads hold the robot up and, for a symmetric layout, are equal.
  EXPECT_NEAR(m.wheel_load.sum(), m.total_mass * kGravity, 1e-9);
  EXPECT_NEAR(m.wheel_load[0], m.wheel_load[1], 1e-9);
}

TEST(OmniModel, ShippedModelsLoadAndAreSslSized) {
  for (const OmniModel& m : {testing::Omni4(), testing::Omni3()}) {
    EXPECT_LT(2 * m.chassis_radius, 0.18) << m.name;
    EXPECT_NEAR(m.total_mass, 2.5, 0.15) << m.name;
    EXPECT_EQ(m.command_delay_frames + m.vision_delay_frames, 4) << m.name;
    EXPECT_NEAR(m.wheel_load.sum(), m.total_mass * kGravity, 1e-9) << m.name;
    EXPECT_GT(m.wheel_load.minCoeff(), 0) << m.name;
  }
}

TEST(OmniModel, UnknownKeyNamesLineColumnAndKnownKeys) {
  std::string yaml = kGood;
  yaml += "motor: {stall_torque: 0.5, frction: 3}\n";
  const std::string e = OmniModelErrorOf(yaml);
  EXPECT_NE(e.find("m.yaml:7:"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'frction' in 'motor'"), std::string::npos) << e;
  EXPECT_NE(e.find("known: "), std::string::npos) << e;
  EXPECT_NE(e.find("stall_torque"), std::string::npos) << e;
}

TEST(OmniModel, WrongTypeIsReportedWithPlace) {
  std::string yaml = kGood;
  yaml.replace(yaml.find("radius: 0.027"), 13, "radius: big");
  const std::string e = OmniModelErrorOf(yaml);
  EXPECT_NE(e.find("m.yaml:6:11: 'radius' in 'wheels': expected a number, got 'big'"), std::string::npos) << e;
}

TEST(OmniModel, MissingFieldIsReported) {
  const std::string e = OmniModelErrorOf("robot: omni\nname: x\nchassis: {mass: 2}\n");
  EXPECT_NE(e.find("missing required key 'wheels'"), std::string::npos) << e;
}

TEST(OmniModel, AllProblemsAreReportedAtOnce) {
  const std::string e = OmniModelErrorOf(
      "robot: omni\nname: x\nchassis: {mass: -2, colour: red}\nwheels: {angles_deg: [0, 90, 180], radius: 0}\n");
  EXPECT_NE(e.find("'mass' in 'chassis': must be positive"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'colour'"), std::string::npos) << e;
  EXPECT_NE(e.find("'radius' in 'wheels': must be positive"), std::string::npos) << e;
}

TEST(OmniModel, PhysicallyInconsistentModelIsRejected) {
  std::string yaml = kGood;
  yaml.replace(yaml.find("[60, 180, 300]"), 14, "[0, 10, 20]");
  const std::string e = OmniModelErrorOf(yaml);
  EXPECT_NE(e.find("do not surround the centre of mass"), std::string::npos) << e;
}

TEST(OmniModel, YamlSyntaxErrorHasLine) {
  const std::string e = OmniModelErrorOf("name: x\nchassis: {mass: 2\n");
  EXPECT_NE(e.find("m.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("YAML syntax error"), std::string::npos) << e;
}

}  // namespace
}  // namespace twinsim
