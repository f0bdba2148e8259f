// The static description of a fixed-base serial arm: a chain of revolute and prismatic
// joints with rigid links, friction and limits (seed 001, section III).
//
// Joint i moves link i relative to link i-1 (link 0 is the fixed base). Its frame is
// placed on link i-1 by `origin` (at q = 0) and moves about or along `axis` (a unit
// vector in that frame): the transform from link i-1 to link i is
//   origin * Rot(axis, q_i)   (revolute)   or   origin * Trans(axis * q_i)   (prismatic),
// which is how URDF describes chains; DH tables are converted to it when loaded. Each
// link's inertial parameters are given in its own frame: mass m, centre of mass c and
// the rotational inertia about the centre of mass. Gravity acts along -z of the base
// frame unless the model says otherwise.
//
// Loaded once, validated once, never changed by a step. LoadArmModel reads URDF
// (through urdfdom) or the project's YAML (docs/arm_models.md), whose joints are either
// a DH table (`dh: standard` or `modified`, converted to the joint table when loaded) or
// a URDF-style joint table (origin xyz/rpy and axis per joint, no `dh` key: what
// WriteArmModelYaml writes), with an optional `effects:` list (arm_effects.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "io/yaml_overrides.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {

enum class JointType { kRevolute, kPrismatic };

struct ArmLink {
  std::string name;
  double mass = 0;                                       // kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();         // m, in the link frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();     // kg m^2, about the centre of mass, link axes
};

struct ArmJoint {
  std::string name;
  JointType type = JointType::kRevolute;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // link i-1 -> joint frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();           // unit, in the joint frame
  double lower = -1e9, upper = 1e9;  // rad or m, position limits
  double velocity_limit = 0;          // rad/s or m/s; 0 = none given
  double effort_limit = 0;            // N·m or N; 0 = none given
  double viscous = 0;                 // N·m·s/rad or N·s/m: tau_f = viscous * qd
  double coulomb = 0;                 // N·m or N: tau_f = coulomb * sign(qd)
  ArmLink child;                      // the link this joint moves
};

// How the Newtonian arm backend (sim/newtonian_arm_backend.h) steps a joint_flexibility's
// spring, damper and motor (docs/arm_backends.md, "Stiff flexible joints"):
enum class FlexibilityIntegrator {
  // The spring's torque of the step's start drives the link; the motor follows by
  // semi-implicit Euler. Stable and accurate only with h sqrt(k / J_eff) well below 1:
  // the automatic physics step takes h sqrt(k / J_eff) <= 0.1.
  kExplicit,
  // The trapezoidal rule (implicit) over spring, damper and motor, solved together with
  // the velocity-level friction: stable for any stiffness, second order, the undamped
  // spring's energy kept; the automatic physics step takes h sqrt(k / J_eff) <= 0.35
  // (the resonance within 1 %).
  kTrapezoidal,
};

// The most joints an arm may have (a humanoid's limb has 7; a snake robot a few dozen).
inline constexpr int kMaxArmJoints = 64;

struct ArmModel {
  std::string name;
  std::string source_path;
  std::vector<ArmJoint> joints;                          // base to tip
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);  // m/s^2, in the base frame
  double sample_time = 0.001;                            // s, the controller's sampling period
  int delay_samples = 0;                                 // samples of delay from command to joint
  ArmEffects effects;                                    // what the rigid model lacks (arm_effects.h)
  FlexibilityIntegrator flexibility_integrator = FlexibilityIntegrator::kExplicit;  // joint_flexibility's step

  int dof() const { return static_cast<int>(joints.size()); }
  // Empty when consistent (positive masses, positive definite inertias satisfying the
  // triangle inequality, unit axes, lower < upper), else every problem.
  std::string Validate() const;
};

// Loads an arm from URDF (.urdf) or the project's YAML (.yaml/.yml). Throws InputError
// "path:line: ..." for a file that is not a fixed-base serial chain of revolute and
// prismatic joints (a loop, a branch, a floating or planar joint, a link without an
// inertial), or any other problem.
ArmModel LoadArmModel(const std::string& path);
// As LoadArmModel, with `overrides` laid over a YAML model's keys (io/yaml_overrides.h)
// before it is read. Throws InputError as above, and for overrides of a URDF model.
ArmModel LoadArmModel(const std::string& path, const YamlOverrides& overrides);
ArmModel LoadArmModelFromUrdfString(const std::string& xml, const std::string& name);
ArmModel LoadArmModelFromYamlString(const std::string& yaml, const std::string& name);

}  // namespace twinsim
