// Rigid-body dynamics of a serial arm (seed 001, section III), as free functions over
// (const ArmModel&, state), Pinocchio style:
//
//   tau = M(q) qdd + C(q, qd) qd + g(q) + tau_friction(qd)
//
// Inverse dynamics by the recursive Newton-Euler algorithm, forward dynamics by
// Featherstone's articulated-body algorithm (one O(n) sweep out and back), the mass
// matrix by the composite-rigid-body algorithm (one pass), both in spatial vectors
// (Featherstone, Rigid Body Dynamics Algorithms, ch. 6 and 7; docs/arm_models.md).
// The *Reference functions build M from n + 1 Newton-Euler passes and solve it: slower,
// kept as the independent check the fast ones are tested against.
//
// Friction (viscous and Coulomb, per joint) is added where `friction` is true. All
// vectors have the model's dof() entries: q in rad or m, qd per second, qdd per second
// squared, tau in N·m or N.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

// Link i's frame relative to link i-1 at joint position q (rad or m).
Eigen::Isometry3d JointTransform(const ArmJoint& joint, double q);

// The pose of each link frame in the base frame (dof() entries).
std::vector<Eigen::Isometry3d> ForwardKinematics(const ArmModel& model, const Eigen::VectorXd& q);

// Joint torques for the motion (q, qd, qdd): recursive Newton-Euler.
Eigen::VectorXd InverseDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, bool friction = true);

// M(q), dof x dof, symmetric positive definite: composite-rigid-body algorithm.
Eigen::MatrixXd MassMatrix(const ArmModel& model, const Eigen::VectorXd& q);
// The same into `mass` (resized to dof x dof; no allocation when it has that size).
void MassMatrix(const ArmModel& model, const Eigen::VectorXd& q, Eigen::MatrixXd* mass);
// M(q) and the bias C(q, qd) qd + g(q) in one pass over the links (what a solve for
// qdd with M in hand needs; no allocation when the outputs have their sizes).
void MassMatrixAndBias(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                       Eigen::MatrixXd* mass, Eigen::VectorXd* bias);

// C(q, qd) qd + g(q) (no friction).
Eigen::VectorXd BiasForces(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

// qdd from the torques (friction included where `friction`): articulated-body
// algorithm.
Eigen::VectorXd ForwardDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, bool friction = true);
// The same into `qdd` (resized to dof; no allocation when it has that size, the hot
// path of the integrators).
void ForwardDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                     const Eigen::VectorXd& tau, bool friction, Eigen::VectorXd* qdd);

// The Newton-Euler references: M from n columns of inverse dynamics (qd = 0, no
// gravity), forward dynamics by solving M qdd = tau - bias - friction with it.
Eigen::MatrixXd MassMatrixReference(const ArmModel& model, const Eigen::VectorXd& q);
Eigen::VectorXd ForwardDynamicsReference(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                         const Eigen::VectorXd& tau, bool friction = true);

// Kinetic energy 1/2 qd' M qd and potential energy -sum m g . p_com (J).
double KineticEnergy(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
double PotentialEnergy(const ArmModel& model, const Eigen::VectorXd& q);

}  // namespace twinsim
