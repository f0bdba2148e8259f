// The coordinates in which the output-error fits move an arm model (arm_output_error.h):
// per joint j of n, x[j] = ln k (the moving link's inertial scale: mass, first moment
// and inertia times k, so a physically consistent link stays consistent), x[n + j] and
// x[2n + j] the logarithms of viscous and Coulomb friction over their units (the start's
// values, or a thousandth of the joint's torque scale where the start has none); with
// offsets x[3n + j] the torque_offset's change in tenths of the joint's torque RMS; with
// stribeck, next, the logarithms of the break-away s - c and the Stribeck speed vs over
// their units (the start's, or the Coulomb unit and a tenth of the joint's RMS speed);
// with presliding (LuGre or a Maxwell-slip element; it needs stribeck), last, the
// logarithm of the bristles' stiffness sigma0 over its unit (the start's, or the
// Coulomb unit over the distance the joint travels in a millisecond at its RMS speed),
// sigma1 set for critical damping against the start's inertia of the joint at the first
// log's first posture, 2 sqrt(sigma0 M_jj).
// x = 0 is the start, its frictions raised to their floors.
//
//   ArmFitCoordinates c(start, logs, /*offsets=*/true, /*stribeck=*/false);
//   std::vector<double> x(c.parameters(), 0.0);
//   ArmModel m = c.Apply(x.data());
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

class ArmFitCoordinates {
 public:
  // What a coordinate is, in the order they come (n of each; offsets and the two Stribeck
  // kinds only when asked for).
  enum class Kind { kScale, kViscous, kCoulomb, kOffset, kBreakaway, kStribeckVelocity, kBristleStiffness };
  // The largest break-away excess s - c, in Coulomb units: static friction up to four
  // times the sliding level, beyond what drives show (friction surveys put it at 1 to 2
  // times). Beyond it the fit finds a sticking that a held-out quarter of the same run
  // accepts and another run rejects (real EMPS: 50 times, free run 94.0 -> 78.3 %).
  static constexpr double kMaxBreakawayExcess = 3.0;

  // The units from `start` and the torques and speeds of `logs`.
  ArmFitCoordinates(const ArmModel& start, const std::vector<ArmLog>& logs, bool offsets, bool stribeck,
                    ArmPresliding presliding = ArmPresliding::kNone);

  int parameters() const {
    return n_ * (3 + (offsets_ ? 1 : 0) + (stribeck_ ? 2 : 0) + (presliding_ != ArmPresliding::kNone ? 1 : 0));
  }
  Kind KindOf(int k) const;
  // "scale of joint 1", ...
  std::string Name(int k) const;
  // The names of coordinates `ks`, in their order.
  std::vector<std::string> Names(const std::vector<int>& ks) const;
  // Within reason: a link scaled by 1/100 to 100, a friction from a millionth of its unit
  // to a thousand times it, an offset within twice the joint's torque RMS, a break-away
  // excess s - c from a thousandth of the Coulomb unit to kMaxBreakawayExcess times it or
  // a tenth of the joint's torque RMS, whichever is larger (a start beyond keeps its
  // own), a Stribeck speed from a
  // thousandth to ten times the joint's RMS speed, a bristle stiffness from a thousandth
  // to ten thousand times its unit.
  void Bounds(int k, double* lower, double* upper) const;
  // The model at coordinates x.
  ArmModel Apply(const double* x) const;
  // The standard error of coordinate k's value from the coordinate's own, `se`: for the
  // logarithmic ones a share of the value (the delta method: d ln v = dx), for an offset
  // N·m or N.
  double ValueError(int k, double se) const {
    return Relative(KindOf(k)) ? se : offset_unit_[k % n_] * se;
  }
  // Whether ValueError gives a kind's error as a share of the value (every kind but the
  // offset, whose coordinate is linear).
  static bool Relative(Kind kind) { return kind != Kind::kOffset; }
  // A kind in a table's heading ("s - c") and as a CSV key ("breakaway"); Name has it
  // in words ("break-away").
  static std::string Heading(Kind kind);
  static std::string Key(Kind kind);

 private:
  ArmModel start_;
  int n_;
  bool offsets_, stribeck_;
  ArmPresliding presliding_;
  Eigen::VectorXd viscous_unit_, coulomb_unit_, offset_unit_, breakaway_unit_, stribeck_velocity_unit_;
  Eigen::VectorXd breakaway_limit_;  // the largest s - c
  Eigen::VectorXd bristle_unit_, joint_inertia_;  // presliding: sigma0's unit; M_jj at the first posture
};

}  // namespace twinsim
