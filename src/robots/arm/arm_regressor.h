// The arm's dynamics are linear in its parameters (seed 001, section III):
//   tau = Y(q, qd, qdd) pi
// with, per link i, the 10 inertial parameters
//   [m, m cx, m cy, m cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]   (inertia about the link frame's origin)
// followed, after all links, by per joint i [viscous_i, coulomb_i]. Not all of them can be
// told apart from torques: FindBaseParameters() reduces them numerically (QR with column
// pivoting on the regressor stacked over random states) to the base set beta = K pi that
// the torques determine, and says which combinations remain.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

inline constexpr int kParametersPerLink = 10;
inline constexpr int kFrictionPerJoint = 2;

// The model's standard parameters (12 n) and their names ("m1", "mcx1", ..., "Izz3", "fv1", "fc1").
Eigen::VectorXd StandardParameters(const ArmModel& model);
std::vector<std::string> StandardParameterNames(const ArmModel& model);
// Writes standard parameters back into a model (inertia moved to the centre of mass).
// Throws InputError when a link's mass is not positive.
ArmModel WithStandardParameters(const ArmModel& model, const Eigen::VectorXd& pi);

// Y(q, qd, qdd): dof x 12 dof.
Eigen::MatrixXd Regressor(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& qdd);

struct BaseParameters {
  std::vector<int> independent;    // standard indices kept, one per base parameter
  Eigen::MatrixXd from_standard;   // r x 12n: beta = from_standard * pi
  std::vector<std::string> names;  // each base parameter as its standard combination
  std::vector<int> unidentifiable; // standard indices that never affect a torque
  int rank() const { return static_cast<int>(independent.size()); }
  // The base columns of a regressor: Y_b with Y pi = Y_b beta.
  Eigen::MatrixXd Reduce(const Eigen::MatrixXd& y) const;
};

// Finds the base parameters from `samples` random states within the joint limits
// (|q| <= pi where unlimited, |qd| <= 2, |qdd| <= 5).
BaseParameters FindBaseParameters(const ArmModel& model, int samples = 200, std::uint64_t seed = 1);

}  // namespace twinsim
