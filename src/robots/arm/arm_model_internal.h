// Private helpers shared by the arm loaders (not part of the public API): the per-format
// file loaders, moving a link's inertial parameters into another frame, lumping rigidly
// joined bodies into one link, and turning Validate()'s findings into an InputError.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "robots/arm/arm_model.h"

namespace twinsim::arm_internal {

// Re-expresses `body` (given in frame B) in frame A, where `a_from_b` maps B to A.
inline ArmLink TransformBody(const ArmLink& body, const Eigen::Isometry3d& a_from_b) {
  ArmLink out = body;
  const Eigen::Matrix3d r = a_from_b.linear();
  out.com = a_from_b * body.com;
  out.inertia = r * body.inertia * r.transpose();
  return out;
}

// Lumps `extra` (expressed in `link`'s frame) into `link`: masses add, the centre of mass
// is the mass-weighted mean, and both inertias move to the new centre of mass by the
// parallel-axis theorem (I_c + m (|r|^2 E - r r^T)). Massless extras change nothing.
inline void AddBody(ArmLink* link, const ArmLink& extra) {
  if (extra.mass == 0 && extra.inertia.isZero()) return;
  const double m = link->mass + extra.mass;
  const Eigen::Vector3d c =
      m > 0 ? Eigen::Vector3d((link->mass * link->com + extra.mass * extra.com) / m) : link->com;
  auto shift = [&c](double mass, const Eigen::Vector3d& at) {
    const Eigen::Vector3d r = at - c;
    return Eigen::Matrix3d(mass * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose()));
  };
  link->inertia = link->inertia + shift(link->mass, link->com) + extra.inertia + shift(extra.mass, extra.com);
  link->mass = m;
  link->com = c;
}

// The loaders behind LoadArmModel(); both throw InputError naming the file.
ArmModel LoadArmUrdfFile(const std::string& path);  // arm_model_urdf.cc
ArmModel LoadArmYamlFile(const std::string& path, const YamlOverrides& overrides = {});  // arm_model_yaml.cc

// Throws InputError listing every problem Validate() finds, each prefixed with `where`.
void ThrowIfInvalid(const ArmModel& model, const std::string& where);

}  // namespace twinsim::arm_internal
