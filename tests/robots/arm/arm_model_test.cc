#include "robots/arm/arm_model.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/error.h"
#include "core/math_constants.h"
#include "test_util.h"

namespace twinsim {
namespace {

constexpr double kDeg = kPi / 180;

// Base-frame pose of every link at q, from the struct's origin/axis definition.
std::vector<Eigen::Isometry3d> LinkPoses(const ArmModel& m, const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> poses;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < m.dof(); ++i) {
    const ArmJoint& j = m.joints[i];
    t = t * j.origin;
    if (j.type == JointType::kRevolute) {
      t = t * Eigen::AngleAxisd(q(i), j.axis);
    } else {
      t = t * Eigen::Translation3d(q(i) * j.axis);
    }
    poses.push_back(t);
  }
  return poses;
}

// What must agree between two descriptions of the same arm, whatever their link frames:
// per link, in the base frame, the joint's axis line, mass, centre of mass and inertia.
struct WorldLink {
  Eigen::Vector3d axis, axis_point, com;
  Eigen::Matrix3d inertia;
  double mass;
};

std::vector<WorldLink> World(const ArmModel& m, const Eigen::VectorXd& q) {
  std::vector<WorldLink> out;
  const auto poses = LinkPoses(m, q);
  for (int i = 0; i < m.dof(); ++i) {
    const Eigen::Isometry3d& t = poses[i];
    const ArmLink& l = m.joints[i].child;
    // The link frame lies on the joint's axis (the motion is about/along it).
    out.push_back({t.linear() * m.joints[i].axis, t.translation(), t * l.com,
                   t.linear() * l.inertia * t.linear().transpose(), l.mass});
  }
  return out;
}

void ExpectSamePhysics(const ArmModel& a, const ArmModel& b, double tol, int samples = 5) {
  ASSERT_EQ(a.dof(), b.dof());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  for (int s = 0; s < samples; ++s) {
    Eigen::VectorXd q(a.dof());
    for (int i = 0; i < a.dof(); ++i) q(i) = s == 0 ? 0.0 : u(rng);
    const auto wa = World(a, q), wb = World(b, q);
    for (int i = 0; i < a.dof(); ++i) {
      SCOPED_TRACE("link " + std::to_string(i + 1) + " sample " + std::to_string(s));
      EXPECT_EQ(a.joints[i].type, b.joints[i].type);
      EXPECT_NEAR((wa[i].axis - wb[i].axis).norm(), 0, tol);
      // Same axis line: the two points differ only along the axis.
      EXPECT_NEAR((wa[i].axis_point - wb[i].axis_point).cross(wa[i].axis).norm(), 0, tol);
      EXPECT_NEAR(wa[i].mass, wb[i].mass, tol);
      EXPECT_NEAR((wa[i].com - wb[i].com).norm(), 0, tol);
      EXPECT_NEAR((wa[i].inertia - wb[i].inertia).norm(), 0, tol);
    }
  }
}

std::string Repo(const std::string& rel) { return testing::SourcePath(rel); }

// The RRR arm of models/rrr.yaml written by hand as URDF in natural frames (z up, arm
// along x, shoulder and elbow about -y so that positive angles raise it). The forearm is
// split into two parts joined by a rotated fixed joint, and a massless flange is fixed
// at the tip, so that lumping is tested too: 1.0 kg at 0.12 m plus 0.3 kg at 0.25 m
// make 1.3 kg at 0.15 m with diag(0.002, 0.016, 0.016) about that point.
const char* kRrrUrdf = R"(<?xml version="1.0"?>
<robot name="rrr">
  <link name="base"/>
  <joint name="waist" type="revolute">
    <parent link="base"/><child link="column"/>
    <origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2.9670597283903604" upper="2.9670597283903604" velocity="6" effort="60"/>
    <dynamics damping="0.5" friction="1.5"/>
  </joint>
  <link name="column">
    <inertial><origin xyz="0 0 -0.1"/><mass value="4.0"/>
      <inertia ixx="0.03" iyy="0.03" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="column"/><child link="upper_arm"/>
    <axis xyz="0 -1 0"/>
    <limit lower="-1.9198621771937625" upper="1.9198621771937625" velocity="6" effort="30"/>
    <dynamics damping="0.3" friction="1.0"/>
  </joint>
  <link name="upper_arm">
    <inertial><origin xyz="0.24 0 0"/><mass value="3.2"/>
      <inertia ixx="0.006" iyy="0.045" izz="0.045" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper_arm"/><child link="forearm"/>
    <origin xyz="0.4 0 0"/>
    <axis xyz="0 -1 0"/>
    <limit lower="-2.6179938779914944" upper="2.6179938779914944" velocity="6" effort="15"/>
    <dynamics damping="0.1" friction="0.5"/>
  </joint>
  <link name="forearm">
    <inertial><origin xyz="0.12 0 0"/><mass value="1.0"/>
      <inertia ixx="0.0015" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="forearm_part" type="fixed">
    <parent link="forearm"/><child link="forearm_end"/>
    <origin xyz="0.2 0 0" rpy="0 0 1.5707963267948966"/>
  </joint>
  <link name="forearm_end">
    <inertial><origin xyz="0 -0.05 0"/><mass value="0.3"/>
      <inertia ixx="0.0021" iyy="0.0005" izz="0.0021" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="flange_joint" type="fixed">
    <parent link="forearm_end"/><child link="flange"/>
    <origin xyz="0 -0.15 0"/>
  </joint>
  <link name="flange"/>
</robot>
)";

// The same arm as a modified (Craig) DH table; inertials in frame i at joint i.
const char* kRrrModified = R"(robot: arm
name: rrr_modified
dh: modified
joints:
  - {type: revolute, a: 0, alpha_deg: 0, d: 0.3, theta_deg: 0,
     link: {mass: 4.0, com: [0, 0, -0.1], inertia: [0.03, 0.03, 0.02, 0, 0, 0]}}
  - {type: revolute, a: 0, alpha_deg: 90, d: 0, theta_deg: 0,
     link: {mass: 3.2, com: [0.24, 0, 0], inertia: [0.006, 0.045, 0.045, 0, 0, 0]}}
  - {type: revolute, a: 0.4, alpha_deg: 0, d: 0, theta_deg: 0,
     link: {mass: 1.3, com: [0.15, 0, 0], inertia: [0.002, 0.016, 0.016, 0, 0, 0]}}
)";

TEST(ArmModel, RrrYamlLoads) {
  const ArmModel m = LoadArmModel(Repo("models/rrr.yaml"));
  ASSERT_EQ(m.dof(), 3);
  EXPECT_EQ(m.name, "rrr");
  EXPECT_EQ(m.joints[0].name, "waist");
  EXPECT_NEAR(m.sample_time, 0.001, 1e-15);
  EXPECT_EQ(m.delay_samples, 1);
  EXPECT_NEAR((m.gravity - Eigen::Vector3d(0, 0, -9.81)).norm(), 0, 1e-15);
  const double mass[] = {4.0, 3.2, 1.3}, effort[] = {60, 30, 15};
  const double coulomb[] = {1.5, 1.0, 0.5}, viscous[] = {0.5, 0.3, 0.1};
  for (int i = 0; i < 3; ++i) {
    const ArmJoint& j = m.joints[i];
    EXPECT_EQ(j.type, JointType::kRevolute);
    EXPECT_NEAR(j.child.mass, mass[i], 1e-15);
    EXPECT_NEAR(j.effort_limit, effort[i], 1e-15);
    EXPECT_NEAR(j.coulomb, coulomb[i], 1e-15);
    EXPECT_NEAR(j.viscous, viscous[i], 1e-15);
    EXPECT_NEAR(j.velocity_limit, 6, 1e-15);
  }
  EXPECT_NEAR(m.joints[1].lower, -110 * kDeg, 1e-12);
  EXPECT_NEAR(m.joints[2].upper, 150 * kDeg, 1e-12);
  // The first link is symmetric about the waist axis: in its (z up) frame the inertia
  // is diagonal with equal x and y moments.
  const Eigen::Matrix3d i1 = m.joints[0].child.inertia;
  EXPECT_NEAR((i1 - Eigen::Vector3d(0.03, 0.03, 0.02).asDiagonal().toDenseMatrix()).norm(), 0, 1e-12);
  // Waist axis vertical through the base origin; shoulder and elbow horizontal.
  const auto w = World(m, Eigen::Vector3d(0.3, -0.4, 0.9));
  EXPECT_NEAR(std::abs(w[0].axis.z()), 1, 1e-12);
  EXPECT_NEAR(w[1].axis.z(), 0, 1e-12);
  EXPECT_NEAR((w[1].axis - w[2].axis).norm(), 0, 1e-12);
  // Stretched out horizontally, gravity loads the shoulder with about half its limit.
  const auto s = World(m, Eigen::Vector3d::Zero());
  const double tau = 9.81 * (s[1].mass * s[1].com.x() + s[2].mass * s[2].com.x());
  EXPECT_NEAR(tau, 14.55, 0.01);
  EXPECT_NEAR(s[2].com.x(), 0.55, 1e-12);
}

TEST(ArmModel, LoadVariantsAddRodAndTipMass) {
  const ArmModel bare = LoadArmModel(Repo("models/rrr.yaml"));
  const ArmModel rod = LoadArmModel(Repo("models/rrr_rod.yaml"));
  const ArmModel tip = LoadArmModel(Repo("models/rrr_rod_tip.yaml"));
  EXPECT_EQ(rod.name, "rrr_rod");
  EXPECT_EQ(tip.name, "rrr_rod_tip");
  EXPECT_EQ(rod.delay_samples, 1);
  EXPECT_NEAR(rod.joints[2].child.mass, 1.3 + 1.22, 1e-12);
  EXPECT_NEAR(tip.joints[2].child.mass, 1.3 + 1.22 + 0.45, 1e-12);
  EXPECT_NEAR(tip.joints[1].child.mass, bare.joints[1].child.mass, 0);
  // Static shoulder torques stretched out: about 14.6, 25.3 and 30.0 N·m (the limit).
  auto shoulder = [](const ArmModel& m) {
    const auto s = World(m, Eigen::Vector3d::Zero());
    return 9.81 * (s[1].mass * s[1].com.x() + s[2].mass * s[2].com.x());
  };
  EXPECT_NEAR(shoulder(rod), 14.55 + 1.22 * 9.81 * 0.90, 0.01);
  EXPECT_NEAR(shoulder(tip), 14.55 + 1.22 * 9.81 * 0.90 + 0.45 * 9.81 * 1.05, 0.01);
  EXPECT_LT(shoulder(tip), 30.0);
  EXPECT_GT(shoulder(tip), 0.99 * 30.0);
}

TEST(ArmModel, UrdfAndBothDhConventionsGiveTheSameArm) {
  const ArmModel yaml = LoadArmModel(Repo("models/rrr.yaml"));
  const ArmModel urdf = LoadArmModelFromUrdfString(kRrrUrdf, "rrr.urdf");
  const ArmModel modified = LoadArmModelFromYamlString(kRrrModified, "rrr_modified.yaml");
  ExpectSamePhysics(yaml, urdf, 1e-12);
  ExpectSamePhysics(yaml, modified, 1e-12);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(urdf.joints[i].lower, yaml.joints[i].lower, 1e-12);
    EXPECT_NEAR(urdf.joints[i].upper, yaml.joints[i].upper, 1e-12);
    EXPECT_NEAR(urdf.joints[i].effort_limit, yaml.joints[i].effort_limit, 1e-12);
    EXPECT_NEAR(urdf.joints[i].velocity_limit, yaml.joints[i].velocity_limit, 1e-12);
    EXPECT_NEAR(urdf.joints[i].viscous, yaml.joints[i].viscous, 1e-12);
    EXPECT_NEAR(urdf.joints[i].coulomb, yaml.joints[i].coulomb, 1e-12);
  }
  // The lumped forearm keeps its own frame and name.
  EXPECT_EQ(urdf.joints[2].child.name, "forearm");
}

// DH frames computed straight from the textbook products, with q added to theta
// (revolute) or d (prismatic).
struct Dh {
  bool prismatic;
  double a, alpha, d, theta;
};

Eigen::Isometry3d DhStep(const Dh& r, double q, bool standard) {
  const double theta = r.theta + (r.prismatic ? 0 : q), d = r.d + (r.prismatic ? q : 0);
  using T = Eigen::Isometry3d;
  const T rz(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ())), rx(Eigen::AngleAxisd(r.alpha, Eigen::Vector3d::UnitX()));
  const T tz(Eigen::Translation3d(0, 0, d)), tx(Eigen::Translation3d(r.a, 0, 0));
  return standard ? T(rz * tz * tx * rx) : T(rx * tx * rz * tz);
}

TEST(ArmModel, DhConversionMatchesTextbookFramesWithPrismaticJoint) {
  const std::vector<Dh> rows = {{false, 0.1, 90 * kDeg, 0.2, 10 * kDeg},
                                {true, 0.05, -90 * kDeg, 0.3, 90 * kDeg},
                                {false, 0.2, 30 * kDeg, 0.07, -20 * kDeg}};
  const Eigen::Vector3d com(0.03, -0.02, 0.05);
  Eigen::Matrix3d inertia;
  inertia << 0.02, 0.001, -0.002, 0.001, 0.03, 0.003, -0.002, 0.003, 0.025;
  for (const bool standard : {true, false}) {
    SCOPED_TRACE(standard ? "standard" : "modified");
    std::string yaml = std::string("robot: arm\nname: rpr\ndh: ") + (standard ? "standard" : "modified") + "\njoints:\n";
    for (const Dh& r : rows) {
      yaml += "  - {type: " + std::string(r.prismatic ? "prismatic" : "revolute") + ", a: " + std::to_string(r.a) +
              ", alpha_deg: " + std::to_string(r.alpha / kDeg) + ", d: " + std::to_string(r.d) +
              ", theta_deg: " + std::to_string(r.theta / kDeg) +
              ", link: {mass: 1.5, com: [0.03, -0.02, 0.05], inertia: [0.02, 0.03, 0.025, 0.001, -0.002, 0.003]}}\n";
    }
    const ArmModel m = LoadArmModelFromYamlString(yaml, "rpr.yaml");
    ASSERT_EQ(m.dof(), 3);
    EXPECT_EQ(m.joints[1].type, JointType::kPrismatic);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    for (int s = 0; s < 4; ++s) {
      const Eigen::Vector3d q(u(rng), u(rng), u(rng));
      const auto world = World(m, q);
      Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
      for (int i = 0; i < 3; ++i) {
        // Standard: joint i moves about z of frame i-1; modified: about z of frame i.
        const Eigen::Isometry3d before = t;
        t = t * DhStep(rows[i], q(i), standard);
        const Eigen::Isometry3d& on_axis = standard ? before : t;
        EXPECT_NEAR((world[i].axis - on_axis.linear().col(2)).norm(), 0, 1e-12);
        EXPECT_NEAR((world[i].axis_point - on_axis.translation()).cross(world[i].axis).norm(), 0, 1e-12);
        EXPECT_NEAR((world[i].com - t * com).norm(), 0, 1e-12);
        EXPECT_NEAR((world[i].inertia - t.linear() * inertia * t.linear().transpose()).norm(), 0, 1e-12);
      }
    }
  }
}

std::string ArmModelErrorOf(const std::function<void()>& load) {
  try {
    load();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

std::string UrdfError(const std::string& xml) {
  return ArmModelErrorOf([&] { LoadArmModelFromUrdfString(xml, "bad.urdf"); });
}

// A two-joint chain with `extra` spliced in before </robot>.
std::string Chain(const std::string& extra, const std::string& second_type = "revolute") {
  return R"(<robot name="bad">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j2" type=")" + second_type + R"(">
    <parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
)" + extra + "</robot>\n";
}

TEST(ArmModel, UrdfChainHelperIsValid) {
  const ArmModel m = LoadArmModelFromUrdfString(Chain(""), "ok.urdf");
  EXPECT_EQ(m.dof(), 2);
  EXPECT_EQ(LoadArmModelFromUrdfString(Chain("", "continuous"), "ok.urdf").joints[1].upper, 1e9);
  EXPECT_EQ(LoadArmModelFromUrdfString(Chain("", "prismatic"), "ok.urdf").joints[1].type, JointType::kPrismatic);
}

TEST(ArmModel, UrdfFloatingJointNamesJointAndLine) {
  const std::string e = UrdfError(Chain("", "floating"));
  EXPECT_NE(e.find("bad.urdf:8: joint 'j2' is floating"), std::string::npos) << e;
}

TEST(ArmModel, UrdfPlanarJointIsRejected) {
  const std::string e = UrdfError(Chain("", "planar"));
  EXPECT_NE(e.find("joint 'j2' is planar"), std::string::npos) << e;
}

TEST(ArmModel, UrdfLinkWithTwoParentsIsALoop) {
  const std::string e = UrdfError(Chain(R"(  <joint name="j3" type="revolute">
    <parent link="base"/><child link="l2"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
)"));
  EXPECT_NE(e.find("bad.urdf:12: link 'l2' is the child of 2 joints ('j2', 'j3'): a closed loop"), std::string::npos) << e;
}

TEST(ArmModel, UrdfCycleWithoutRootIsRejected) {
  const std::string e = UrdfError(R"(<robot name="cycle">
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="ab" type="continuous"><parent link="a"/><child link="b"/></joint>
  <joint name="ba" type="continuous"><parent link="b"/><child link="a"/></joint>
</robot>
)");
  // Found in the text before urdfdom (which says only "no root link" and has no lines).
  EXPECT_NE(e.find("bad.urdf:5: joint 'ba' closes a loop of links (a -> b -> a)"), std::string::npos) << e;
}

TEST(ArmModel, UrdfCommentedOutJointClosesNoLoop) {
  const ArmModel m = LoadArmModelFromUrdfString(
      Chain(R"(  <!-- <joint name="back" type="fixed"><parent link="l2"/><child link="base"/></joint> -->
)"),
      "ok.urdf");
  EXPECT_EQ(m.dof(), 2);
}

TEST(ArmModel, UrdfThatIsNotUtf8IsRefusedWithItsLine) {
  // Latin-1 in a comment (a file saved in the wrong encoding) ...
  std::string e = UrdfError(Chain("  <!-- caf\xE9 -->\n"));
  EXPECT_NE(e.find("not UTF-8 text: byte 0xE9 does not start a complete UTF-8 character"), std::string::npos) << e;
  // ... and text ending inside a character: TinyXML read past the end of such text
  // (found by urdf_fuzz; tests/fuzz/crashes/urdf/).
  e = UrdfError("<robot name=\"r\"><link name=\"a\"/>\n<mass value=\"1.\xF1\xA7");
  EXPECT_NE(e.find("bad.urdf:2: not UTF-8 text: byte 0xF1"), std::string::npos) << e;
  // Well-formed UTF-8 passes (a name in Greek).
  const ArmModel m = LoadArmModelFromUrdfString(Chain("  <!-- \xCE\xB1\xCF\x81\xCE\xB8\xCF\x81\xCF\x89\xCF\x83\xCE\xB7 -->\n"), "ok.urdf");
  EXPECT_EQ(m.dof(), 2);
}

TEST(ArmModel, UrdfBranchNamesTheLink) {
  const std::string e = UrdfError(Chain(R"(  <joint name="j3" type="revolute">
    <parent link="l1"/><child link="l3"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="l3"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
)"));
  EXPECT_NE(e.find("bad.urdf:7: link 'l1' has 2 child joints"), std::string::npos) << e;
  EXPECT_NE(e.find("a branch"), std::string::npos) << e;
}

TEST(ArmModel, UrdfMovingLinkWithoutInertialNamesTheLink) {
  std::string xml = Chain("");
  const std::size_t at = xml.find(R"(<link name="l2">)");
  xml.replace(at, xml.find("</link>", at) + 7 - at, R"(<link name="l2"/>)");
  const std::string e = UrdfError(xml);
  EXPECT_NE(e.find("bad.urdf:12: link 'l2', moved by joint 'j2', has no <inertial>"), std::string::npos) << e;
}

TEST(ArmModel, UrdfThatUrdfdomRejectsNamesTheFile) {
  EXPECT_NE(UrdfError("<robot name='x'><link name='a'/><joint").find("bad.urdf: not a valid URDF"), std::string::npos);
  const std::string missing = ArmModelErrorOf([] { LoadArmModel("/nonexistent/arm.urdf"); });
  EXPECT_NE(missing.find("/nonexistent/arm.urdf: cannot open file"), std::string::npos) << missing;
  const std::string ext = ArmModelErrorOf([] { LoadArmModel("arm.sdf"); });
  EXPECT_NE(ext.find("arm.sdf: "), std::string::npos) << ext;
  EXPECT_NE(ext.find(".urdf, .yaml or .yml"), std::string::npos) << ext;
}

std::string YamlError(const std::string& yaml) {
  return ArmModelErrorOf([&] { LoadArmModelFromYamlString(yaml, "bad.yaml"); });
}

TEST(ArmModel, YamlUnknownKeyWrongTypeAndMissingFieldHavePlaces) {
  const std::string yaml = R"(robot: arm
name: bad
dh: standard
joints:
  - type: revolute
    a: 0.4
    alpha_deg: zero
    d: 0
    theta_deg: 0
    frction: 1
    link: {mass: 1, inertia: [0.1, 0.1, 0.1, 0, 0, 0]}
  - type: revolute
    a: 0.3
    alpha_deg: 0
    d: 0
    link: {mass: 1, com: [0, 0], inertia: [0.1, 0.1, 0.1, 0, 0, 0]}
)";
  const std::string e = YamlError(yaml);
  EXPECT_NE(e.find("bad.yaml:10:5: unknown key 'frction' in 'joint 1'"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.yaml:7:16: 'alpha_deg' in 'joint 1': expected a number, got 'zero'"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.yaml:12:5: missing required key 'theta_deg' in 'joint 2'"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.yaml:16:26: 'com' in 'joint 2.link': expected 3 numbers, got 2"), std::string::npos) << e;
}

TEST(ArmModel, YamlRejectsMisusedLimitsAndBadConvention) {
  const std::string e = YamlError(R"(robot: arm
name: bad
dh: craig
joints:
  - {type: revolute, a: 0, alpha_deg: 0, d: 0, theta_deg: 0, lower: -1, upper_deg: 10,
     link: {mass: 1, inertia: [0.1, 0.1, 0.1, 0, 0, 0]}}
)");
  EXPECT_NE(e.find("bad.yaml:3:5: 'dh': unknown value 'craig' (known: standard, modified)"), std::string::npos) << e;
  EXPECT_NE(e.find("'lower' in 'joint 1': a revolute joint's limits are 'lower_deg' and 'upper_deg'"), std::string::npos) << e;
}

TEST(ArmModel, ValidateCatchesNegativeMassAndTriangleInequality) {
  ArmModel m = LoadArmModel(Repo("models/rrr.yaml"));
  EXPECT_EQ(m.Validate(), "");
  m.joints[1].child.mass = -1;
  m.joints[2].child.inertia = Eigen::Vector3d(0.01, 0.01, 0.03).asDiagonal();
  const std::string e = m.Validate();
  EXPECT_NE(e.find("joint 2 'shoulder', link 'upper_arm': mass must be positive"), std::string::npos) << e;
  EXPECT_NE(e.find("joint 3 'elbow', link 'forearm': inertia violates the triangle inequality"), std::string::npos) << e;
  m = LoadArmModel(Repo("models/rrr.yaml"));
  m.joints[0].axis = Eigen::Vector3d(0, 0, 2);
  m.joints[0].lower = 1;
  m.joints[0].upper = -1;
  EXPECT_NE(m.Validate().find("axis must be a unit vector"), std::string::npos);
  EXPECT_NE(m.Validate().find("lower limit 1 must be below upper limit -1"), std::string::npos);
  // The loaders run Validate too.
  const std::string y = YamlError(R"(robot: arm
name: bad
dh: modified
joints:
  - {type: revolute, a: 0, alpha_deg: 0, d: 0, theta_deg: 0,
     link: {mass: 1, inertia: [0.01, 0.01, 0.03, 0, 0, 0]}}
)");
  EXPECT_NE(y.find("bad.yaml: joint 1 'joint1', link 'link1': inertia violates the triangle inequality"), std::string::npos) << y;
}

TEST(ArmModel, KukaLwr4UrdfLoadsSevenRevoluteJoints) {
  const std::string path = Repo("../shared/realdata/kuka_lwr4/kuka_lwr4.urdf");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  const ArmModel m = LoadArmModel(path);
  ASSERT_EQ(m.dof(), 7);
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(m.joints[i].name, "lwr_" + std::to_string(i) + "_joint");
    EXPECT_EQ(m.joints[i].type, JointType::kRevolute);
    EXPECT_GT(m.joints[i].child.mass, 0);
  }
  // The box and the base link are fixed to the world: the first joint sits 0.11 m above
  // the base link, which the fixed joint places at (-0.25, 0, 1) in the box's frame.
  EXPECT_NEAR((m.joints[0].origin.translation() - Eigen::Vector3d(-0.25, 0, 1.11)).norm(), 0, 1e-12);
  EXPECT_NEAR(m.joints[1].child.mass, 2.7, 1e-12);
  EXPECT_NEAR(m.joints[6].child.mass, 0.3, 1e-12);
  EXPECT_NEAR(m.joints[0].viscous, 1.0, 1e-12);
  EXPECT_NEAR(m.joints[0].coulomb, 0.5, 1e-12);
  EXPECT_NEAR(m.joints[0].effort_limit, 176, 1e-12);
  EXPECT_NEAR(m.joints[1].axis.y(), -1, 1e-12);
}

}  // namespace
}  // namespace twinsim
