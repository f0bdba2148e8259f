// The output-error fits' coordinates (src/analysis/arm_fit_coordinates.h): x = 0 is the
// start, and the break-away excess s - c stays within what drives show.
#include "analysis/arm_fit_coordinates.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace {

// A cart of 10 kg on a prismatic joint; its torque RMS 10 N, its RMS speed 0.5 m/s.
ArmModel Cart(double coulomb) {
  ArmModel m = LoadArmModelFromYamlString(
      "robot: arm\nname: cart\njoints:\n  - name: slide\n    type: prismatic\n    axis: [1, 0, 0]\n"
      "    link: {name: cart, mass: 10, com: [0, 0, 0], inertia: [0.1, 0.1, 0.1, 0, 0, 0]}\n",
      "cart.yaml");
  m.joints[0].coulomb = coulomb;
  return m;
}

ArmLog CartLog() {
  ArmLog log;
  log.dof = 1;
  const int n = 100;
  log.t = Eigen::VectorXd::LinSpaced(n, 0, 0.99);
  log.q = Eigen::MatrixXd::Zero(n, 1);
  log.qd = Eigen::MatrixXd::Constant(n, 1, 0.5);
  log.qdd = Eigen::MatrixXd::Zero(n, 1);
  log.tau = Eigen::MatrixXd::Constant(n, 1, 10.0);
  log.sample_period = 0.01;
  return log;
}

// The model's break-away excess s - c at the break-away coordinate's bound.
double ExcessAtBound(const ArmModel& start, bool upper) {
  const ArmFitCoordinates c(start, {CartLog()}, /*offsets=*/false, /*stribeck=*/true);
  const int k = 3;  // scale, viscous, Coulomb, then the break-away (one joint)
  EXPECT_EQ(c.KindOf(k), ArmFitCoordinates::Kind::kBreakaway);
  double lower = 0, up = 0;
  c.Bounds(k, &lower, &up);
  std::vector<double> x(static_cast<std::size_t>(c.parameters()), 0.0);
  x[k] = upper ? up : lower;
  const JointEffects& e = c.Apply(x.data()).effects.joint(0);
  return e.stribeck_static - e.stribeck_coulomb;
}

TEST(ArmFitCoordinates, TheBreakawayStaysWithinThreeTimesTheCoulombLevel) {
  // Coulomb 20 N: s - c up to 60 N (3 x 20, above a tenth of the 10 N torque RMS), down to
  // 0.02 N.
  EXPECT_NEAR(ExcessAtBound(Cart(20), true), ArmFitCoordinates::kMaxBreakawayExcess * 20, 1e-9);
  EXPECT_NEAR(ExcessAtBound(Cart(20), false), 1e-3 * 20, 1e-12);
  // A joint that starts without Coulomb friction (its unit a thousandth of the torque
  // RMS, 0.01 N) may still break away by a tenth of the torque RMS, 1 N.
  EXPECT_NEAR(ExcessAtBound(Cart(0), true), 1.0, 1e-9);
}

TEST(ArmFitCoordinates, AStartBeyondTheLimitKeepsItsOwnBreakaway) {
  ArmModel start = Cart(2);
  AddArmEffect({"stribeck_friction", 0, {{"c", 2}, {"s", 30}, {"vs", 0.01}}}, 1, &start.effects);
  // Its excess 28 N is beyond 3 x 2 N: the range reaches it (x = 0 at the upper edge).
  EXPECT_NEAR(ExcessAtBound(start, true), 28, 1e-9);
  const ArmFitCoordinates c(start, {CartLog()}, false, true);
  std::vector<double> x(static_cast<std::size_t>(c.parameters()), 0.0);
  EXPECT_NEAR(c.Apply(x.data()).effects.joint(0).stribeck_static, 30, 1e-9);
}

}  // namespace
}  // namespace twinsim
