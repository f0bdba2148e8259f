// The analytic rigid-body model of omni robots: the reference the physics engines are
// checked against.
//
// Each robot is one rigid body whose wheels roll without slipping along their rolling
// direction and slide across it against Coulomb roller friction. With body velocity
// v = (vx, vy, omega) and wheel speeds w = J v (omni_kinematics.h), the reduced
// equations of motion (Lagrange-d'Alembert on SE(2)) are
//   (M + J^T I_w J) dv/dt = (m omega vy, -m omega vx, 0) + J^T tau + F_roller
// with M = diag(m, m, I_z) over chassis and wheels and I_w the wheels' spin inertia.
// Integrated by classic RK4 per step. No walls, no robot-robot contact, no traction
// limit: valid below the wheels' friction limit (docs/backends.md).
#pragma once

#include <memory>
#include <vector>

#include "backends/omni_engine.h"

namespace twinsim {

std::unique_ptr<OmniEngine> MakeAnalyticOmniEngine(const std::vector<OmniModel>& robots,
                                                   const FieldModel& field);

}  // namespace twinsim
