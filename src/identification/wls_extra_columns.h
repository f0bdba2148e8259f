// The weighted least squares' unknowns beyond the base parameters (wls_identification.h):
// a torque offset per joint, position friction's knots and a position torque's, as
// columns of each joint's equations, and how their estimates become the model's
// effects. Internal to identification/.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "identification/wls_identification.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {

// The unknowns after the r base parameters, each in one joint's equations: a torque
// offset per joint (with torque_offsets), then per moving joint the position friction's
// d_2..d_K (with position_friction_knots K), then per moving joint the position torque's
// levels (with position_torque_knots K: e_2..e_K beside an offset, else e_1..e_K), in the
// summary's order.
struct ExtraColumns {
  enum class Kind { kOffset, kFriction, kTorque };
  int offsets = 0;
  int knots = 0;         // position friction's
  int torque_knots = 0;  // position torque's
  std::vector<int> joint;  // per extra column
  std::vector<int> knot;   // per extra column: its knot (0-based; -1 for an offset)
  std::vector<Kind> kind;  // per extra column
  Eigen::VectorXd from, to;

  ExtraColumns(int dof, bool with_offsets, int position_knots, int position_torque_knots,
               const std::vector<int>& position_joints, const Eigen::VectorXd& knots_from,
               const Eigen::VectorXd& knots_to)
      : offsets(with_offsets ? dof : 0),
        knots(position_knots),
        torque_knots(position_torque_knots),
        from(knots_from),
        to(knots_to) {
    for (int j = 0; j < offsets; ++j) Add(j, -1, Kind::kOffset);
    for (int j : position_joints)
      for (int k = 1; k < knots; ++k) Add(j, k, Kind::kFriction);
    for (int j : position_joints)
      for (int k = offsets > 0 ? 1 : 0; k < torque_knots; ++k) Add(j, k, Kind::kTorque);
  }
  int size() const { return static_cast<int>(joint.size()); }
  // Extra column c's entry in its joint's equation at position q and velocity qd.
  double Value(int c, double q, double qd) const {
    const auto i = static_cast<std::size_t>(c);
    const int j = joint[i];
    switch (kind[i]) {
      case Kind::kOffset: return 1;
      case Kind::kFriction: return ((qd > 0) - (qd < 0)) * KnotWeight(from[j], to[j], knots, knot[i], q);
      case Kind::kTorque: return KnotWeight(from[j], to[j], torque_knots, knot[i], q);
    }
    return 0;
  }

 private:
  void Add(int j, int k, Kind what) {
    joint.push_back(j);
    knot.push_back(k);
    kind.push_back(what);
  }
};

// The joints with knots of their own: every joint that moves, with position friction or
// a position torque.
std::vector<int> PositionJoints(bool profiles, const std::vector<bool>& still);

// With position friction: each knotted joint's dry level at its knots, the consistent
// Coulomb level plus d_k, into summary->position_* and into `result` as the joint's
// constant level (the lowest knot's; a level below zero is held at zero and noted) and a
// position_friction effect with the rest.
void SetPositionFriction(const ExtraColumns& extras, ArmModel* result, WlsIdentificationSummary* summary);

// With a position torque: each knotted joint's levels p_k, minus its columns' estimates
// (measured - model, as the offsets; 0 at the first knot beside an offset), into
// summary->torque_levels and into `result` as a position_torque effect.
void SetPositionTorque(const ExtraColumns& extras, ArmModel* result, WlsIdentificationSummary* summary);

}  // namespace twinsim
