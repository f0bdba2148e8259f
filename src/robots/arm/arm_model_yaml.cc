// Reading an ArmModel from the project's YAML: a DH table (`dh: standard|modified`) or,
// without `dh`, a URDF-style joint table (each joint's origin xyz + rpy and axis in the
// parent link's frame), with inertial parameters, limits and friction; the schema is
// documented in docs/arm_models.md.
//
// DH rows are converted to the struct's `origin * Rot(z, q)` form. Standard DH,
//   T_i = RotZ(theta_i + q) TransZ(d_i) TransX(a_i) RotX(alpha_i),
// splits into Pre_i = RotZ(theta_i) TransZ(d_i), the motion RotZ(q) (or TransZ(q)), and
// Post_i = TransX(a_i) RotX(alpha_i); the motion commutes with TransZ(d_i), so
// origin_i = Post_{i-1} Pre_i, and the DH frame i (where the YAML gives link i's
// inertials) sits at Post_i in the struct's link frame. Modified DH (Craig),
//   T_i = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i + q) TransZ(d_i),
// gives origin_i = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i) TransZ(d_i) directly,
// and its frame i is the struct's link frame.
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_internal.h"

namespace twinsim {
namespace {

constexpr double kDegToRad = kPi / 180.0;

Eigen::Isometry3d RotZ(double angle) { return Eigen::Isometry3d(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())); }
Eigen::Isometry3d RotX(double angle) { return Eigen::Isometry3d(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX())); }
Eigen::Isometry3d TransZ(double d) { return Eigen::Isometry3d(Eigen::Translation3d(0, 0, d)); }
Eigen::Isometry3d TransX(double a) { return Eigen::Isometry3d(Eigen::Translation3d(a, 0, 0)); }

struct DhRow {
  double a = 0;      // m
  double alpha = 0;  // rad
  double d = 0;      // m
  double theta = 0;  // rad, offset added to a revolute joint's q
};

ArmModel ReadArmModel(const YAML::Node& file_root, const std::string& path, int depth);

YAML::Node Resolve(const YAML::Node& root, const std::string& path, int depth) {
  return ResolveExtends(root, path, depth, [](const YAML::Node& base, const std::string& base_path, int d) {
    ReadArmModel(base, base_path, d);
  });
}

// Reads mass, centre of mass and inertia [ixx, iyy, izz, ixy, ixz, iyz] (about the
// centre of mass) of a link or a load.
void ReadBody(YamlMap& m, ArmLink* body) {
  m.Require("mass", &body->mass, Positive(1e5));
  std::vector<double> com;
  if (m.Get("com", &com, 3, InRange(-100, 100))) body->com = Eigen::Vector3d(com[0], com[1], com[2]);
  std::vector<double> i;
  if (m.Require("inertia", &i, 6, InRange(-1e5, 1e5))) {
    body->inertia << i[0], i[3], i[4],
                     i[3], i[1], i[5],
                     i[4], i[5], i[2];
  }
}

// The keys of the other joint table, for a hint when a file mixes the two.
const char* kDhKeys[] = {"a", "alpha_deg", "d", "theta_deg"};
const char* kUrdfKeys[] = {"origin", "axis"};

void ReadDhRow(YamlMap& jm, DhRow* row) {
  for (const char* key : kUrdfKeys) {
    if (jm.Has(key)) {
      jm.Error(key, std::string("'") + key + "' belongs to a URDF-style joint table; a DH table ('dh: ...') gives "
                                            "a, alpha_deg, d and theta_deg");
    }
  }
  jm.Require("a", &row->a, InRange(-100, 100));
  if (jm.Require("alpha_deg", &row->alpha)) row->alpha *= kDegToRad;
  jm.Require("d", &row->d, InRange(-100, 100));
  if (jm.Require("theta_deg", &row->theta)) row->theta *= kDegToRad;
}

// A URDF-style joint: `origin: {xyz: [x, y, z], rpy: [roll, pitch, yaw]}` (m, rad; the
// rotation is Rz(yaw) Ry(pitch) Rx(roll), as in URDF) places the joint frame on the
// parent link; `axis: [x, y, z]` (normalised) is the motion's axis in that frame.
void ReadUrdfPlacement(YamlMap& jm, ArmJoint* j) {
  for (const char* key : kDhKeys) {
    if (jm.Has(key)) {
      jm.Error(key, std::string("'") + key + "' is a DH parameter; give 'dh: standard' or 'dh: modified' at the top "
                                            "level, or place the joint with 'origin' and 'axis'");
    }
  }
  if (jm.Has("origin")) {
    YamlMap om(jm.Child("origin"), jm.path(), jm.context() + ".origin", jm.errors());
    std::vector<double> xyz{0, 0, 0}, rpy{0, 0, 0};
    om.Get("xyz", &xyz, 3, InRange(-100, 100));
    om.Get("rpy", &rpy, 3);
    om.Finish();
    if (xyz.size() == 3 && rpy.size() == 3) {
      j->origin = Eigen::Isometry3d::Identity();
      j->origin.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
      j->origin.linear() = (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
                               .toRotationMatrix();
    }
  }
  std::vector<double> axis;
  if (jm.Require("axis", &axis, 3)) {
    const Eigen::Vector3d a(axis[0], axis[1], axis[2]);
    if (!(a.norm() > 1e-9)) {
      jm.Error("axis", "must not be zero");
    } else {
      j->axis = a.normalized();
    }
  }
}

// Position limits: a DH table gives revolute ones in degrees (lower_deg, upper_deg), a
// URDF-style table in radians like URDF (lower, upper); prismatic ones are in metres.
void ReadLimits(YamlMap& jm, bool dh, const std::string& type, ArmJoint* j) {
  const bool degrees = dh && j->type == JointType::kRevolute;
  const std::string lower_key = degrees ? "lower_deg" : "lower";
  const std::string upper_key = degrees ? "upper_deg" : "upper";
  for (const std::string wrong : {degrees ? "lower" : "lower_deg", degrees ? "upper" : "upper_deg"}) {
    if (jm.Has(wrong)) {
      const std::string table = dh ? "" : " in a URDF-style table (radians or metres, as in URDF)";
      jm.Error(wrong, std::string("a ") + type + " joint's limits are '" + lower_key + "' and '" + upper_key + "'" +
                          table);
    }
  }
  const double unit = degrees ? kDegToRad : 1.0;
  if (jm.Get(lower_key, &j->lower)) j->lower *= unit;
  if (jm.Get(upper_key, &j->upper)) j->upper *= unit;
  if (jm.Has(lower_key) && jm.Has(upper_key) && !(j->lower < j->upper)) {
    jm.Error(upper_key, "must be above '" + lower_key + "'");
  }
}

ArmModel ReadArmModel(const YAML::Node& file_root, const std::string& path, int depth) {
  ErrorList errors;
  ArmModel model;
  model.source_path = path;
  const YAML::Node root = Resolve(file_root, path, depth);
  RequireModelKind(root, path, RobotKind::kArm);
  YamlMap top(root, path, "", &errors);
  std::string kind = "arm";
  top.Get("robot", &kind, {"arm"});
  top.Has("extends");  // resolved above
  top.Require("name", &model.name);
  std::vector<double> gravity;
  if (top.Get("gravity", &gravity, 3)) model.gravity = Eigen::Vector3d(gravity[0], gravity[1], gravity[2]);
  top.Get("sample_time", &model.sample_time, Positive(10));
  top.Get("delay_samples", &model.delay_samples, InRange(0, 100000));
  std::string flex_integrator = "explicit";
  if (top.Get("flexibility_integrator", &flex_integrator, std::vector<std::string>{"explicit", "trapezoidal"})) {
    model.flexibility_integrator =
        flex_integrator == "trapezoidal" ? FlexibilityIntegrator::kTrapezoidal : FlexibilityIntegrator::kExplicit;
  }
  // With `dh` the joints are DH rows; without it they are URDF-style (origin and axis).
  std::string convention;
  const bool dh = top.Has("dh");
  if (dh) top.Get("dh", &convention, std::vector<std::string>{"standard", "modified"});

  // Link inertials as written: in the DH frame i of the chosen convention.
  std::vector<DhRow> rows;
  if (top.Has("joints")) {
    const YAML::Node list = top.Child("joints");
    if (!list.IsSequence() || list.size() == 0) {
      top.Error("joints", "expected a list of joints");
    } else if (list.size() > static_cast<std::size_t>(kMaxArmJoints)) {
      top.Error("joints", "has " + std::to_string(list.size()) + " joints; at most " + std::to_string(kMaxArmJoints) +
                              " are supported");
    } else {
      for (std::size_t k = 0; k < list.size(); ++k) {
        const std::string label = "joint " + std::to_string(k + 1);
        YamlMap jm(list[k], path, label, &errors);
        ArmJoint j;
        DhRow row;
        j.name = "joint" + std::to_string(k + 1);
        jm.Get("name", &j.name);
        std::string type = "revolute";
        jm.Require("type", &type, std::vector<std::string>{"revolute", "prismatic"});
        j.type = type == "prismatic" ? JointType::kPrismatic : JointType::kRevolute;
        if (dh) {
          ReadDhRow(jm, &row);
        } else {
          ReadUrdfPlacement(jm, &j);
        }

        ReadLimits(jm, dh, type, &j);
        jm.Get("velocity_limit", &j.velocity_limit, NonNegative(1e4));
        jm.Get("effort_limit", &j.effort_limit, NonNegative(1e7));
        jm.Get("viscous", &j.viscous, NonNegative(1e6));
        jm.Get("coulomb", &j.coulomb, NonNegative(1e7));

        if (jm.Has("link")) {
          YamlMap lm(jm.Child("link"), path, label + ".link", &errors);
          j.child.name = "link" + std::to_string(k + 1);
          lm.Get("name", &j.child.name);
          ReadBody(lm, &j.child);
          lm.Finish();
        } else {
          jm.Missing("link");
        }
        jm.Finish();
        model.joints.push_back(j);
        rows.push_back(row);
      }
    }
  } else {
    top.Missing("joints");
  }

  // Loads clamped to a link (a rod, a tip mass), in the same frame as that link's inertials.
  if (top.Has("loads")) {
    const YAML::Node list = top.Child("loads");
    if (!list.IsSequence()) {
      top.Error("loads", "expected a list of loads");
    } else {
      for (std::size_t k = 0; k < list.size(); ++k) {
        YamlMap lm(list[k], path, "load " + std::to_string(k + 1), &errors);
        ArmLink load;
        lm.Get("name", &load.name);
        int on = 0;
        const int n = static_cast<int>(model.joints.size());
        const bool where = lm.Require("link", &on, InRange(1, std::max(1, n)));
        ReadBody(lm, &load);
        lm.Finish();
        if (where && on <= n) arm_internal::AddBody(&model.joints[on - 1].child, load);
      }
    }
  }
  if (top.Has("effects")) ReadArmEffects(top.Child("effects"), path, &model, &errors);
  top.Finish();
  errors.ThrowIfAny();

  if (!dh) {
    arm_internal::ThrowIfInvalid(model, path);
    return model;
  }
  const bool standard = convention == "standard";
  Eigen::Isometry3d previous_post = Eigen::Isometry3d::Identity();
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    ArmJoint& j = model.joints[k];
    const DhRow& r = rows[k];
    j.axis = Eigen::Vector3d::UnitZ();
    if (standard) {
      const Eigen::Isometry3d post = TransX(r.a) * RotX(r.alpha);
      j.origin = previous_post * RotZ(r.theta) * TransZ(r.d);
      j.child = arm_internal::TransformBody(j.child, post);
      previous_post = post;
    } else {
      j.origin = RotX(r.alpha) * TransX(r.a) * RotZ(r.theta) * TransZ(r.d);
    }
  }
  arm_internal::ThrowIfInvalid(model, path);
  return model;
}

}  // namespace

namespace arm_internal {

ArmModel LoadArmYamlFile(const std::string& path, const YamlOverrides& overrides) {
  const YAML::Node root = LoadYamlFile(path);
  return ReadArmModel(overrides.empty() ? root : ApplyYamlOverrides(root, overrides, path), path, 0);
}

}  // namespace arm_internal

ArmModel LoadArmModelFromYamlString(const std::string& yaml, const std::string& name) {
  YAML::Node root = LoadYamlString(yaml, name);
  if (!root.IsMap()) throw InputError(SourceLocation{name, 1}, "expected a YAML mapping at the top level");
  return ReadArmModel(root, name, 0);
}

}  // namespace twinsim
