// The URDF-style YAML joint table and the writer: any model written and loaded back is
// the same model.
#include "robots/arm/arm_model_yaml_writer.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A chain with turned joint frames (all three rpy angles), a prismatic joint, a
// continuous joint (no limits), products of inertia and a tool link lumped by a fixed joint.
const char* kUrdf = R"(<?xml version="1.0"?>
<robot name="odd arm">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.7 1.9"/>
    <axis xyz="0 0.6 0.8"/>
    <limit lower="-2.5" upper="2.0" effort="40" velocity="3"/>
    <dynamics damping="0.4" friction="1.1"/>
  </joint>
  <link name="l1">
    <inertial><origin xyz="0.01 0.02 0.15" rpy="0.2 0.1 -0.4"/><mass value="3.1"/>
      <inertia ixx="0.03" ixy="0.001" ixz="-0.002" iyy="0.025" iyz="0.0015" izz="0.012"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.4" rpy="1.5707963267948966 0 0"/>
    <axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.25" effort="200" velocity="0.5"/>
  </joint>
  <link name="l2">
    <inertial><origin xyz="0.05 0 0"/><mass value="1.2"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="spin" type="continuous">
    <parent link="l2"/><child link="l3"/>
    <origin xyz="0.2 0.01 0" rpy="0 1.5707963267948966 0"/>
    <axis xyz="0 0 1"/>
    <limit effort="5" velocity="8"/>
  </joint>
  <link name="l3">
    <inertial><origin xyz="0 0.01 0.03"/><mass value="0.4"/>
      <inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0004" iyz="0" izz="0.0002"/></inertial>
  </link>
  <joint name="tool_joint" type="fixed">
    <parent link="l3"/><child link="tool"/>
    <origin xyz="0 0 0.08"/>
  </joint>
  <link name="tool">
    <inertial><mass value="0.3"/><inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/></inertial>
  </link>
</robot>
)";

void ExpectSameModel(const ArmModel& a, const ArmModel& b, double tol) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_LE((a.gravity - b.gravity).cwiseAbs().maxCoeff(), tol);
  EXPECT_EQ(a.sample_time, b.sample_time);
  EXPECT_EQ(a.delay_samples, b.delay_samples);
  ASSERT_EQ(a.dof(), b.dof());
  for (int i = 0; i < a.dof(); ++i) {
    const ArmJoint& x = a.joints[static_cast<std::size_t>(i)];
    const ArmJoint& y = b.joints[static_cast<std::size_t>(i)];
    SCOPED_TRACE(x.name);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.type, y.type);
    EXPECT_LE((x.origin.matrix() - y.origin.matrix()).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.axis - y.axis).cwiseAbs().maxCoeff(), tol);
    EXPECT_EQ(x.lower, y.lower);
    EXPECT_EQ(x.upper, y.upper);
    EXPECT_EQ(x.velocity_limit, y.velocity_limit);
    EXPECT_EQ(x.effort_limit, y.effort_limit);
    EXPECT_EQ(x.viscous, y.viscous);
    EXPECT_EQ(x.coulomb, y.coulomb);
    EXPECT_EQ(x.child.name, y.child.name);
    EXPECT_EQ(x.child.mass, y.child.mass);
    EXPECT_LE((x.child.com - y.child.com).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.child.inertia - y.child.inertia).cwiseAbs().maxCoeff(), tol);
  }
}

TEST(ArmModelYamlWriter, UrdfWrittenAsYamlLoadsBackAsTheSameModel) {
  const ArmModel urdf = LoadArmModelFromUrdfString(kUrdf, "odd.urdf");
  ASSERT_EQ(urdf.dof(), 3);
  const std::string dir = testing::TempDir("arm_yaml_writer");
  WriteArmModelYaml(dir + "/odd.yaml", urdf, "round trip\nof odd.urdf");
  const std::string text = testing::ReadText(dir + "/odd.yaml");
  EXPECT_EQ(text.rfind("# round trip\n# of odd.urdf\nrobot: arm\nname: \"odd arm\"\n", 0), 0u) << text;
  EXPECT_EQ(text.find("dh:"), std::string::npos);
  const ArmModel back = LoadArmModel(dir + "/odd.yaml");
  // Numbers are exact; the rotations pass through roll, pitch and yaw.
  ExpectSameModel(urdf, back, 1e-12);
}

TEST(ArmModelYamlWriter, DhModelsRoundTrip) {
  for (const char* rel : {"models/rrr.yaml", "models/rrr_rod_tip.yaml"}) {
    SCOPED_TRACE(rel);
    const ArmModel m = LoadArmModel(testing::SourcePath(rel));
    ExpectSameModel(m, LoadArmModelFromYamlString(FormatArmModelYaml(m), "again.yaml"), 1e-12);
  }
}

// The real KUKA's URDF (../shared/realdata, not shipped): skipped, and said, where absent.
TEST(ArmModelYamlWriter, TheKukaRoundTrips) {
  const std::string path = testing::SourcePath("../shared/realdata/kuka_lwr4/kuka_lwr4.urdf");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no real data at " << path;
  const ArmModel m = LoadArmModel(path);
  ExpectSameModel(m, LoadArmModelFromYamlString(FormatArmModelYaml(m), "again.yaml"), 1e-12);
}

TEST(ArmModelYamlWriter, UrdfStyleTableRejectsDhKeysUnknownKeysAndZeroAxes) {
  auto error = [](const std::string& yaml) {
    try {
      LoadArmModelFromYamlString(yaml, "t.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string e = error(R"(robot: arm
name: t
joints:
  - type: revolute
    origin: {xyz: [0, 0, 0.1], rpy: [0, 0, 0], rotation: 1}
    axis: [0, 0, 0]
    a: 0.3
    lower_deg: -90
    link: {mass: 1, inertia: [0.1, 0.1, 0.1, 0, 0, 0]}
  - type: prismatic
    link: {mass: 1, inertia: [0.1, 0.1, 0.1, 0, 0, 0]}
)");
  EXPECT_NE(e.find("t.yaml:5:48: unknown key 'rotation' in 'joint 1.origin' (known: rpy, xyz)"), std::string::npos) << e;
  EXPECT_NE(e.find("t.yaml:6:11: 'axis' in 'joint 1': must not be zero"), std::string::npos) << e;
  EXPECT_NE(e.find("t.yaml:7:8: 'a' in 'joint 1': 'a' is a DH parameter; give 'dh: standard' or 'dh: modified'"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("'lower_deg' in 'joint 1': a revolute joint's limits are 'lower' and 'upper' in a URDF-style table"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("missing required key 'axis' in 'joint 2'"), std::string::npos) << e;
  const std::string mixed = error(R"(robot: arm
name: t
dh: standard
joints:
  - {type: revolute, a: 0, alpha_deg: 0, d: 0, theta_deg: 0, axis: [0, 0, 1],
     link: {mass: 1, inertia: [0.1, 0.1, 0.1, 0, 0, 0]}}
)");
  EXPECT_NE(mixed.find("'axis' in 'joint 1': 'axis' belongs to a URDF-style joint table"), std::string::npos) << mixed;
}

TEST(ArmModelYamlWriter, UrdfStyleTableMatchesTheDhTableOfTheRrrArm) {
  // The RRR arm written by hand as a URDF-style table: the same physics as models/rrr.yaml.
  const ArmModel dh = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const ArmModel table = LoadArmModelFromYamlString(R"(robot: arm
name: rrr
sample_time: 0.001
delay_samples: 1
joints:
  - name: waist
    type: revolute
    origin: {xyz: [0, 0, 0.30]}
    axis: [0, 0, 1]
    lower: -2.9670597283903604
    upper: 2.9670597283903604
    velocity_limit: 6
    effort_limit: 60
    viscous: 0.5
    coulomb: 1.5
    link: {name: column, mass: 4.0, com: [0, 0, -0.10], inertia: [0.03, 0.03, 0.02, 0, 0, 0]}
  - name: shoulder
    type: revolute
    origin: {rpy: [1.5707963267948966, 0, 0]}
    axis: [0, 0, 1]
    lower: -1.9198621771937625
    upper: 1.9198621771937625
    velocity_limit: 6
    effort_limit: 30
    viscous: 0.3
    coulomb: 1.0
    link: {name: upper_arm, mass: 3.2, com: [0.24, 0, 0], inertia: [0.006, 0.045, 0.045, 0, 0, 0]}
  - name: elbow
    type: revolute
    origin: {xyz: [0.40, 0, 0]}
    axis: [0, 0, 1]
    lower: -2.6179938779914944
    upper: 2.6179938779914944
    velocity_limit: 6
    effort_limit: 15
    viscous: 0.1
    coulomb: 0.5
    link: {name: forearm, mass: 1.3, com: [0.15, 0, 0], inertia: [0.002, 0.016, 0.016, 0, 0, 0]}
)",
                                                    "rrr_table.yaml");
  ExpectSameModel(dh, table, 1e-12);
}


void ExpectSameEffects(const ArmEffects& a, const ArmEffects& b) {
  ASSERT_EQ(a.joints.size(), b.joints.size());
  for (std::size_t j = 0; j < a.joints.size(); ++j) {
    SCOPED_TRACE("joint " + std::to_string(j + 1));
    const JointEffects& x = a.joints[j];
    const JointEffects& y = b.joints[j];
    EXPECT_EQ(x.viscous, y.viscous);
    EXPECT_EQ(x.coulomb_positive, y.coulomb_positive);
    EXPECT_EQ(x.coulomb_negative, y.coulomb_negative);
    EXPECT_EQ(x.stribeck_coulomb, y.stribeck_coulomb);
    EXPECT_EQ(x.stribeck_static, y.stribeck_static);
    EXPECT_EQ(x.stribeck_velocity, y.stribeck_velocity);
    EXPECT_EQ(x.torque_offset, y.torque_offset);
    EXPECT_EQ(x.saturation, y.saturation);
    EXPECT_EQ(x.time_delay, y.time_delay);
    EXPECT_EQ(x.stiffness, y.stiffness);
    EXPECT_EQ(x.flex_damping, y.flex_damping);
    EXPECT_EQ(x.motor_inertia, y.motor_inertia);
  }
  EXPECT_EQ(a.payload_mass, b.payload_mass);
  EXPECT_EQ(a.payload_position, b.payload_position);
}

TEST(ArmModelYamlWriter, EveryEffectKindRoundTripsExactly) {
  ArmModel m = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  // Every kind, awkward numbers (no short decimal form), both Coulomb forms, a negative offset.
  AddArmEffect({"viscous_friction", 0, {{"b", 0.1 / 3}}}, 3, &m.effects);
  AddArmEffect({"coulomb_friction", 0, {{"c_pos", 0.4}, {"c_neg", 0.6 + 1e-13}}}, 3, &m.effects);
  AddArmEffect({"coulomb_friction", 1, {{"c", 2.0 / 7}}}, 3, &m.effects);
  AddArmEffect({"stribeck_friction", 1, {{"c", 0.3}, {"s", 0.8}, {"vs", 0.05}}}, 3, &m.effects);
  AddArmEffect({"torque_offset", 1, {{"tau0", -0.123456789012345678}}}, 3, &m.effects);
  AddArmEffect({"torque_saturation", 2, {{"limit", 14.5}}}, 3, &m.effects);
  AddArmEffect({"time_delay", 2, {{"delay", 0.0021}}}, 3, &m.effects);
  AddArmEffect({"joint_flexibility", 2, {{"k", 253}, {"damping", 0.2}, {"motor_inertia", 0.01}}}, 3, &m.effects);
  AddArmEffect({"joint_flexibility", 0, {{"k", 1e4}, {"motor_inertia", 0.02}}}, 3, &m.effects);  // no damping
  AddArmEffect({"payload", -1, {{"mass", 0.45}, {"x", 0.35}, {"z", -1.0 / 3}}}, 3, &m.effects);
  const std::string text = FormatArmModelYaml(m);
  EXPECT_NE(text.find("  - {name: torque_offset, joint: 2, tau0: -0.12345678901234568}\n"), std::string::npos) << text;
  EXPECT_NE(text.find("  - {name: payload, joint: null, mass: 0.45, x: 0.35, y: 0, z: -0.3333333333333333}\n"),
            std::string::npos)
      << text;
  const ArmModel back = LoadArmModelFromYamlString(text, "effects.yaml");
  ExpectSameModel(m, back, 1e-12);
  ExpectSameEffects(m.effects, back.effects);
  EXPECT_EQ(ListArmEffects(back.effects).size(), 10u);
  // And again: the effects' text is a fixed point (the rpy angles are exact to 1e-15 only).
  const std::string again = FormatArmModelYaml(back);
  EXPECT_EQ(again.substr(again.find("effects:")), text.substr(text.find("effects:")));
  // A model without effects writes no effects list.
  EXPECT_EQ(FormatArmModelYaml(LoadArmModel(testing::SourcePath("models/rrr.yaml"))).find("effects:"), std::string::npos);
}

}  // namespace
}  // namespace twinsim
