#include "identification/wls_extra_columns.h"

#include <cstdio>
#include <string>

#include "robots/arm/arm_model.h"

namespace twinsim {

std::vector<int> PositionJoints(bool profiles, const std::vector<bool>& still) {
  std::vector<int> joints;
  for (std::size_t j = 0; profiles && j < still.size(); ++j)
    if (!still[j]) joints.push_back(static_cast<int>(j));
  return joints;
}

// With position friction: each knotted joint's dry level at its knots, the consistent
// Coulomb level plus d_k, into summary->position_* and into `result` as the joint's
// constant level (the lowest knot's; a level below zero is held at zero and noted) and a
// position_friction effect with the rest.
void SetPositionFriction(const ExtraColumns& extras, ArmModel* result, WlsIdentificationSummary* summary) {
  const int n = result->dof(), knots = extras.knots, r = summary->base_parameters;
  if (knots == 0) return;
  summary->position_knots = knots;
  summary->position_levels.resize(n, knots);
  for (int j = 0; j < n; ++j)
    summary->position_levels.row(j).setConstant(result->joints[static_cast<std::size_t>(j)].coulomb);
  for (int c = 0; c < extras.size(); ++c) {
    if (extras.kind[static_cast<std::size_t>(c)] != ExtraColumns::Kind::kFriction) continue;
    summary->position_levels(extras.joint[static_cast<std::size_t>(c)], extras.knot[static_cast<std::size_t>(c)]) +=
        summary->consistent[r + c];
  }
  for (const int j : summary->position_joints) {
    auto levels = summary->position_levels.row(j);
    for (int k = 0; k < knots; ++k) {
      if (levels[k] >= 0) continue;
      char note[160];
      std::snprintf(note, sizeof note, "the Coulomb friction of joint %d at knot %d came out negative (%.6g): held at 0",
                    j + 1, k + 1, levels[k]);
      summary->position_notes.push_back(note);
      levels[k] = 0;
    }
    const double lowest = levels.minCoeff();
    result->joints[static_cast<std::size_t>(j)].coulomb = lowest;
    ArmEffect effect{"position_friction", j, {{"from", extras.from[j]}, {"to", extras.to[j]}}};
    for (int k = 0; k < knots; ++k) effect.parameters[ProfileLevelKey('c', k)] = levels[k] - lowest;
    AddArmEffect(effect, n, &result->effects);
  }
}

// With a position torque: each knotted joint's levels p_k, minus its columns' estimates
// (measured - model, as the offsets; 0 at the first knot beside an offset), into
// summary->torque_levels and into `result` as a position_torque effect.
void SetPositionTorque(const ExtraColumns& extras, ArmModel* result, WlsIdentificationSummary* summary) {
  const int n = result->dof(), knots = extras.torque_knots, r = summary->base_parameters;
  if (knots == 0) return;
  summary->torque_knots = knots;
  summary->torque_levels = Eigen::MatrixXd::Zero(n, knots);
  for (int c = 0; c < extras.size(); ++c) {
    if (extras.kind[static_cast<std::size_t>(c)] != ExtraColumns::Kind::kTorque) continue;
    summary->torque_levels(extras.joint[static_cast<std::size_t>(c)], extras.knot[static_cast<std::size_t>(c)]) =
        -summary->consistent[r + c];
  }
  for (const int j : summary->position_joints) {
    ArmEffect effect{"position_torque", j, {{"from", extras.from[j]}, {"to", extras.to[j]}}};
    for (int k = 0; k < knots; ++k) effect.parameters[ProfileLevelKey('p', k)] = summary->torque_levels(j, k);
    AddArmEffect(effect, n, &result->effects);
  }
}

}  // namespace twinsim
