// The analytic rigid-body model of omni robots: the reference the physics engines are
// checked against.
//
// Each robot is one rigid body whose wheels roll without slipping along their rolling
// direction and slide across it against Coulomb roller friction. With body velocity
// v = (vx, vy, omega) and wheel speeds w = J v (omni_kinematics.h), the reduced
// equations of motion (Lagrange-d'Alembert on SE(2), in the robot frame about its
// centre) are
//   (M + J^T I_w J) dv/dt = ad*_v (M v) + J^T tau + F_roller
//   ad*_v p = (omega p_y, -omega p_x, v_y p_x - v_x p_y)
// with M the rigid-body mass matrix of chassis and wheels about the centre (the
// wheels put the centre of mass slightly off it; OmniModel::RigidBodyMass) and I_w the
// wheels' spin inertia.
// Integrated by classic RK4 per step. No walls, no robot-robot contact, no traction
// limit: valid below the wheels' friction limit (docs/backends.md), which grip() checks
// on every step (a wheel's rolling force and roller friction against wheel_friction
// times its static load) and counts where it is passed.
#pragma once

#include <memory>
#include <vector>

#include "engines/omni_engine.h"

namespace twinsim {

std::unique_ptr<OmniEngine> MakeAnalyticOmniEngine(const std::vector<OmniModel>& robots,
                                                   const FieldModel& field);

}  // namespace twinsim
