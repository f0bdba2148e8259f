// Rigid-body dynamics of a serial arm (seed 001, section III): inverse dynamics by the
// recursive Newton-Euler algorithm, the mass matrix, bias forces and forward dynamics,
// as free functions over (const ArmModel&, state), Pinocchio style.
//
//   tau = M(q) qdd + C(q, qd) qd + g(q) + tau_friction(qd)
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

// M(q), dof x dof, symmetric positive definite.
Eigen::MatrixXd MassMatrix(const ArmModel& model, const Eigen::VectorXd& q);

// C(q, qd) qd + g(q) (no friction).
Eigen::VectorXd BiasForces(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

// qdd from the torques (friction included where `friction`).
Eigen::VectorXd ForwardDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, bool friction = true);

// Kinetic energy 1/2 qd' M qd and potential energy -sum m g . p_com (J).
double KineticEnergy(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
double PotentialEnergy(const ArmModel& model, const Eigen::VectorXd& q);

}  // namespace twinsim
