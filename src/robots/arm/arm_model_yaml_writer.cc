#include "robots/arm/arm_model_yaml_writer.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "io/atomic_file.h"
#include "io/yaml_number.h"

namespace twinsim {
namespace {

std::string Vector(const Eigen::Vector3d& v) {
  return "[" + YamlNumber(v.x()) + ", " + YamlNumber(v.y()) + ", " + YamlNumber(v.z()) + "]";
}

// A YAML scalar for a name: plain when safe, else double-quoted.
std::string Text(const std::string& s) {
  bool plain = !s.empty();
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) plain = false;
  }
  if (plain && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '-' || s[0] == '.')) plain = false;
  for (const char* word : {"true", "false", "yes", "no", "on", "off", "null", "y", "n"}) {
    std::string lower;
    for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == word) plain = false;
  }
  if (plain) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// URDF's roll, pitch, yaw with R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d RollPitchYaw(const Eigen::Matrix3d& r) {
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  if (std::hypot(r(0, 0), r(1, 0)) < 1e-10) {
    // Gimbal lock: only roll - yaw (or roll + yaw) is defined; put it all in roll.
    return Eigen::Vector3d(std::atan2(-r(1, 2), r(1, 1)), pitch, 0);
  }
  return Eigen::Vector3d(std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0)));
}

}  // namespace

std::string FormatArmModelYaml(const ArmModel& model, const std::string& comment) {
  std::ostringstream s;
  if (!comment.empty()) {
    std::istringstream lines(comment);
    std::string line;
    while (std::getline(lines, line)) s << "# " << line << "\n";
  }
  s << "robot: arm\n";
  s << "name: " << Text(model.name) << "\n";
  s << "gravity: " << Vector(model.gravity) << "   # m/s^2, base frame\n";
  s << "sample_time: " << YamlNumber(model.sample_time) << "   # s\n";
  s << "delay_samples: " << model.delay_samples << "\n";
  if (model.flexibility_integrator == FlexibilityIntegrator::kTrapezoidal) {
    s << "flexibility_integrator: trapezoidal   # joint_flexibility's step (docs/arm_backends.md)\n";
  }
  s << "# URDF-style joint table (no 'dh' key): origin and axis in the parent link's frame,\n"
       "# limits in rad (revolute) or m (prismatic), link inertials in the link frame about\n"
       "# the centre of mass, inertia as [ixx, iyy, izz, ixy, ixz, iyz] in kg m^2.\n";
  s << "joints:\n";
  for (const ArmJoint& j : model.joints) {
    const Eigen::Vector3d rpy = RollPitchYaw(j.origin.linear());
    s << "  - name: " << Text(j.name) << "\n";
    s << "    type: " << (j.type == JointType::kPrismatic ? "prismatic" : "revolute") << "\n";
    s << "    origin: {xyz: " << Vector(j.origin.translation()) << ", rpy: " << Vector(rpy) << "}\n";
    s << "    axis: " << Vector(j.axis) << "\n";
    const ArmJoint defaults;
    if (j.lower != defaults.lower) s << "    lower: " << YamlNumber(j.lower) << "\n";
    if (j.upper != defaults.upper) s << "    upper: " << YamlNumber(j.upper) << "\n";
    s << "    velocity_limit: " << YamlNumber(j.velocity_limit) << "\n";
    s << "    effort_limit: " << YamlNumber(j.effort_limit) << "\n";
    s << "    viscous: " << YamlNumber(j.viscous) << "\n";
    s << "    coulomb: " << YamlNumber(j.coulomb) << "\n";
    const ArmLink& l = j.child;
    s << "    link:\n";
    s << "      name: " << Text(l.name.empty() ? j.name + "_link" : l.name) << "\n";
    s << "      mass: " << YamlNumber(l.mass) << "\n";
    s << "      com: " << Vector(l.com) << "\n";
    const Eigen::Matrix3d& i = l.inertia;
    s << "      inertia: [" << YamlNumber(i(0, 0)) << ", " << YamlNumber(i(1, 1)) << ", " << YamlNumber(i(2, 2)) << ", "
      << YamlNumber(0.5 * (i(0, 1) + i(1, 0))) << ", " << YamlNumber(0.5 * (i(0, 2) + i(2, 0))) << ", "
      << YamlNumber(0.5 * (i(1, 2) + i(2, 1))) << "]\n";
  }
  const std::vector<ArmEffect> effects = ListArmEffects(model.effects);
  if (!effects.empty()) {
    s << "# What the rigid model lacks (docs/arm_backends.md); joints by 1-based number.\n";
    s << "effects:\n";
    for (const ArmEffect& e : effects) {
      s << "  - {name: " << e.name << ", joint: " << (e.joint < 0 ? std::string("null") : std::to_string(e.joint + 1));
      // In the vocabulary's parameter order, as the documentation lists them.
      for (const std::string& key : ArmEffectParameters(e.name)) {
        const auto it = e.parameters.find(key);
        if (it != e.parameters.end()) s << ", " << key << ": " << YamlNumber(it->second);
      }
      s << "}\n";
    }
  }
  return s.str();
}

void WriteArmModelYaml(const std::string& path, const ArmModel& model, const std::string& comment) {
  WriteFileAtomically(path, FormatArmModelYaml(model, comment));
}

}  // namespace twinsim
