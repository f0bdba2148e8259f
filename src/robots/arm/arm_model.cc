// ArmModel's consistency checks and the loader that picks URDF or YAML by extension.
#include "robots/arm/arm_model.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "robots/arm/arm_model_internal.h"

namespace twinsim {
namespace {

bool Finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

// Problems of one link's inertial parameters, each as "what: detail".
void CheckLink(const ArmLink& link, const std::string& label, std::vector<std::string>* out) {
  std::ostringstream s;
  if (!std::isfinite(link.mass) || link.mass <= 0) {
    s.str("");
    s << label << ": mass must be positive, got " << link.mass << " kg";
    out->push_back(s.str());
  }
  if (!Finite(link.com)) out->push_back(label + ": centre of mass is not finite");
  const Eigen::Matrix3d& i = link.inertia;
  if (!Finite(i)) {
    out->push_back(label + ": inertia is not finite");
    return;
  }
  const double scale = std::max(1e-12, i.cwiseAbs().maxCoeff());
  if (!i.isApprox(i.transpose(), 1e-9) && (i - i.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    out->push_back(label + ": inertia is not symmetric");
    return;
  }
  // Principal moments: all positive, and each at most the sum of the other two
  // (the triangle inequality every real mass distribution satisfies).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (i + i.transpose()));
  const Eigen::Vector3d p = eig.eigenvalues();  // ascending
  const double tol = 1e-9 * std::max(1e-12, p.cwiseAbs().sum());
  if (p(0) <= 0) {
    s.str("");
    s << label << ": inertia must be positive definite, principal moments " << p(0) << ", " << p(1)
      << ", " << p(2) << " kg m^2";
    out->push_back(s.str());
  } else if (p(2) > p(0) + p(1) + tol) {
    s.str("");
    s << label << ": inertia violates the triangle inequality, principal moments " << p(0) << " + " << p(1)
      << " < " << p(2) << " kg m^2";
    out->push_back(s.str());
  }
}

}  // namespace

std::string ArmModel::Validate() const {
  std::vector<std::string> problems;
  std::ostringstream s;
  if (joints.empty()) problems.push_back("the arm has no moving joints");
  if (!(sample_time > 0) || !std::isfinite(sample_time)) problems.push_back("sample_time must be positive");
  if (delay_samples < 0) problems.push_back("delay_samples must not be negative");
  if (!Finite(gravity)) problems.push_back("gravity is not finite");
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const ArmJoint& j = joints[k];
    const std::string label = "joint " + std::to_string(k + 1) + " '" + j.name + "'";
    if (!Finite(j.origin.matrix())) problems.push_back(label + ": origin is not finite");
    if (!Finite(j.axis) || std::abs(j.axis.norm() - 1) > 1e-9) {
      s.str("");
      s << label << ": axis must be a unit vector, got [" << j.axis.transpose() << "]";
      problems.push_back(s.str());
    }
    if (!(j.lower < j.upper)) {
      s.str("");
      s << label << ": lower limit " << j.lower << " must be below upper limit " << j.upper;
      problems.push_back(s.str());
    }
    auto non_negative = [&](double v, const char* what) {
      if (!(v >= 0) || !std::isfinite(v)) {
        s.str("");
        s << label << ": " << what << " must not be negative, got " << v;
        problems.push_back(s.str());
      }
    };
    non_negative(j.velocity_limit, "velocity limit");
    non_negative(j.effort_limit, "effort limit");
    non_negative(j.viscous, "viscous friction");
    non_negative(j.coulomb, "Coulomb friction");
    // position_friction's levels may dip below zero where the joint's other Coulomb
    // friction covers them: its dry level must not go negative anywhere along the travel
    // (linear between the knots, so at a knot if anywhere).
    const JointEffects e = effects.joint(static_cast<int>(k));
    for (int knot = 0; knot < e.friction_profile.knots; ++knot) {
      const double level = j.coulomb + std::min(e.coulomb_positive, e.coulomb_negative) +
                           e.friction_profile.levels[static_cast<std::size_t>(knot)];
      if (level >= 0) continue;
      s.str("");
      s << label << ": its dry friction would be " << level << " at position_friction's knot " << knot + 1
        << " (the joint's Coulomb friction plus c" << knot + 1 << "): it must not be negative";
      problems.push_back(s.str());
      break;
    }
    CheckLink(j.child, label + ", link '" + j.child.name + "'", &problems);
  }
  std::string all;
  for (const auto& p : problems) all += (all.empty() ? "" : "\n") + p;
  return all;
}

namespace arm_internal {

void ThrowIfInvalid(const ArmModel& model, const std::string& where) {
  const std::string problems = model.Validate();
  if (problems.empty()) return;
  ErrorList errors;
  std::istringstream lines(problems);
  std::string line;
  while (std::getline(lines, line)) errors.Add(SourceLocation{where}, line);
  errors.ThrowIfAny();
}

}  // namespace arm_internal

ArmModel LoadArmModel(const std::string& path) { return LoadArmModel(path, {}); }

ArmModel LoadArmModel(const std::string& path, const YamlOverrides& overrides) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".urdf") {
    if (!overrides.empty())
      throw InputError(SourceLocation{path}, "cannot set '" + overrides.front().key +
                                                 "': keys can be set in the project's YAML models, not in URDF");
    return arm_internal::LoadArmUrdfFile(path);
  }
  if (ext == ".yaml" || ext == ".yml") return arm_internal::LoadArmYamlFile(path, overrides);
  throw InputError(SourceLocation{path},
                   "cannot tell the arm model's format from the extension '" + ext +
                       "' (expected .urdf, .yaml or .yml)");
}

}  // namespace twinsim
