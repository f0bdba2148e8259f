// Pre-sliding friction (stribeck_friction with sigma0 and sigma1: LuGre's bristles, or
// with maxwell: 1 a Maxwell-slip element) in the Newtonian arm backend, on a 90 kg cart
// on a prismatic joint: LuGre against a fine RK4 of its equations below break-away, the
// Maxwell-slip element's exact elastic deflection F / sigma0 that springs back whole,
// both sliding at the speed of the static friction curve whose steady state they are, on
// every engine, and the model file's refusals.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <iostream>
#include <memory>
#include <string>

#include "analysis/arm_replay.h"
#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace {

constexpr double kCartMass = 90;        // kg
constexpr double kSliding = 20;         // N: c
constexpr double kBreakaway = 25;       // N: s
constexpr double kStribeckSpeed = 0.01;  // m/s: vs
constexpr double kViscous = 200;        // N s/m
constexpr double kSigma0 = 1e6;         // N/m: 20 um of deflection at the sliding level

ArmModel Cart(bool presliding, bool maxwell = false) {
  ArmModel m = LoadArmModelFromYamlString(
      "robot: arm\nname: cart\ngravity: [0, 0, -9.81]\nsample_time: 0.001\njoints:\n"
      "  - name: axis\n    type: prismatic\n    axis: [1, 0, 0]\n    viscous: 200\n"
      "    link: {name: cart, mass: 90, com: [0, 0, 0], inertia: [1, 1, 1, 0, 0, 0]}\n",
      "cart");
  ArmEffect stribeck{"stribeck_friction", 0, {{"c", kSliding}, {"s", kBreakaway}, {"vs", kStribeckSpeed}}};
  if (presliding) {
    stribeck.parameters["sigma0"] = kSigma0;
    stribeck.parameters["sigma1"] = 2 * std::sqrt(kSigma0 * kCartMass);  // the bristles critically damped
    if (maxwell) stribeck.parameters["maxwell"] = 1;
  }
  AddArmEffect(stribeck, m.dof(), &m.effects);
  return m;
}

// The cart's position (m) and velocity (m/s) at every sample under force(t) from rest at 0.
struct CartRun {
  Eigen::VectorXd q, qd;
};
CartRun Push(const std::string& engine, const ArmModel& m, double seconds, const std::function<double(double)>& force) {
  std::unique_ptr<ArmBackend> b = MakeArmBackend(engine, m);
  const int samples = static_cast<int>(std::lround(seconds / m.sample_time));
  b->Reset(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1));
  CartRun run{Eigen::VectorXd(samples), Eigen::VectorXd(samples)};
  Eigen::VectorXd applied;
  for (int k = 0; k < samples; ++k) {
    b->Step(Eigen::VectorXd::Constant(1, force(k * m.sample_time)), &applied);
    run.q[k] = b->q()[0];
    run.qd[k] = b->qd()[0];
  }
  return run;
}

// The cart's LuGre equations by RK4 at 1 us, written out apart from the backend:
//   m x'' = F - sigma0 z - sigma1 z' - b x',  z' = x' - sigma0 |x'| z / g(x'),
//   g(v) = c + (s - c) exp(-(v / vs)^2). Returns x at each 1 ms sample.
Eigen::VectorXd LugreReference(double seconds, const std::function<double(double)>& force) {
  const double sigma1 = 2 * std::sqrt(kSigma0 * kCartMass);
  const auto derivative = [&](double t, const Eigen::Vector3d& s) {  // (x, v, z)
    const double v = s[1], r = v / kStribeckSpeed;
    const double g = kSliding + (kBreakaway - kSliding) * std::exp(-r * r);
    const double dz = v - kSigma0 * std::abs(v) * s[2] / g;
    return Eigen::Vector3d(v, (force(t) - kSigma0 * s[2] - sigma1 * dz - kViscous * v) / kCartMass, dz);
  };
  const int samples = static_cast<int>(std::lround(seconds * 1000)), per_sample = 1000;
  const double h = 1e-3 / per_sample;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::VectorXd x(samples);
  for (int k = 0; k < samples; ++k) {
    // The force is held over each sample, as the backend receives it.
    const double t0 = k * 1e-3;
    const auto held = [&](double, const Eigen::Vector3d& y) { return derivative(t0, y); };
    for (int i = 0; i < per_sample; ++i) {
      const Eigen::Vector3d k1 = held(0, s), k2 = held(0, s + 0.5 * h * k1), k3 = held(0, s + 0.5 * h * k2),
                            k4 = held(0, s + h * k3);
      s += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    x[k] = s[0];
  }
  return x;
}

TEST(PreslidingFriction, BelowBreakAwayTheCartDeflectsAsTheFineReferenceWhereStaticFrictionHoldsIt) {
  // 10 N for 0.5 s, then none for 0.5 s. The bristles' spring against the cart rings at
  // sqrt(sigma0 / m) = 105 rad/s, critically damped; the backend steps 1 ms with the
  // bristles integrated exactly over a step, against RK4 at 1 us. LuGre's pre-sliding is
  // partly plastic (the bristles slip while they move: z' = x' - a z with a > 0), so the
  // cart deflects beyond F / sigma0 = 10 um and keeps some of it after the release. The
  // static friction holds the cart exactly still.
  const auto force = [](double t) { return t < 0.5 ? 10.0 : 0.0; };
  const Eigen::VectorXd reference = LugreReference(1.0, force);
  for (const std::string engine : {"analytic", "ode", "bullet"}) {
    const CartRun lugre = Push(engine, Cart(true), 1.0, force);
    const CartRun rigid = Push(engine, Cart(false), 1.0, force);
    const double held = lugre.q[499], back = lugre.q[999];
    const double gap = (lugre.q - reference).cwiseAbs().maxCoeff();
    std::cout << "[measured] " << engine << ": deflection under 10 N " << held * 1e6 << " um (reference "
              << reference[499] * 1e6 << ", F / sigma0 10), left after release " << back * 1e6 << " um (reference "
              << reference[999] * 1e6 << "); largest gap " << gap * 1e6 << " um\n";
    EXPECT_LT(gap, 0.03 * reference.cwiseAbs().maxCoeff()) << engine;
    EXPECT_GT(held, 10 / kSigma0) << engine;   // at least the elastic part
    EXPECT_LT(std::abs(back), held) << engine;  // and some of it springs back
    EXPECT_EQ(rigid.q.cwiseAbs().maxCoeff(), 0.0) << engine;
  }
}

TEST(PreslidingFriction, AMaxwellSlipElementDeflectsByForceOverStiffnessAndSpringsBackWhole) {
  // The same 10 N for 0.5 s: a Maxwell-slip element is a spring until its force reaches
  // the friction level, so the cart settles at F / sigma0 = 10 um and returns to 0.
  const auto force = [](double t) { return t < 0.5 ? 10.0 : 0.0; };
  const double expected = 10 / kSigma0;
  for (const std::string engine : {"analytic", "ode", "bullet"}) {
    const CartRun run = Push(engine, Cart(true, true), 1.0, force);
    std::cout << "[measured] " << engine << ": Maxwell-slip deflection under 10 N " << run.q[499] * 1e6
              << " um, left after release " << run.q[999] * 1e6 << " um\n";
    EXPECT_NEAR(run.q[499], expected, 0.01 * expected) << engine;
    EXPECT_NEAR(run.q[999], 0, 0.01 * expected) << engine;
  }
}

TEST(PreslidingFriction, SlidesAtTheSpeedOfTheStaticCurveItIsTheSteadyStateOf) {
  // 60 N: g(v) + b v = 60 at v = (60 - 20) / 200 = 0.2 m/s (the Stribeck excess is
  // exp(-400) there); m / b = 0.45 s, so after 7 s the speed is within 2e-7 of it.
  const auto force = [](double) { return 60.0; };
  const double expected = (60 - kSliding) / kViscous;
  for (const std::string engine : {"analytic", "ode", "bullet"}) {
    const CartRun lugre = Push(engine, Cart(true), 7.0, force);
    const CartRun rigid = Push(engine, Cart(false), 7.0, force);
    const CartRun maxwell = Push(engine, Cart(true, true), 7.0, force);
    EXPECT_NEAR(maxwell.qd[maxwell.qd.size() - 1], expected, 1e-4 * expected) << engine;
    const double v_lugre = lugre.qd[lugre.qd.size() - 1], v_rigid = rigid.qd[rigid.qd.size() - 1];
    std::cout << "[measured] " << engine << ": sliding at " << v_lugre << " m/s (static curve " << v_rigid
              << ", closed form " << expected << "); positions after 7 s " << lugre.q[lugre.q.size() - 1] << " and "
              << rigid.q[rigid.q.size() - 1] << " m\n";
    EXPECT_NEAR(v_lugre, expected, 1e-4 * expected) << engine;
    EXPECT_NEAR(v_rigid, expected, 1e-4 * expected) << engine;
    // Positions part by the start: the bristles' damping sigma1 z' holds the cart back
    // while they deflect (about a millimetre here), then both slide alike.
    EXPECT_NEAR(lugre.q[lugre.q.size() - 1], rigid.q[rigid.q.size() - 1], 2e-3) << engine;
  }
}

TEST(PreslidingFriction, BreaksAwayWithTheStaticModelUnderASlowRamp) {
  // A force rising at 10 N/s: the static model slides from s = 25 N on and reaches 1 mm/s
  // a little later (the force keeps rising while the cart gathers speed). LuGre's
  // bristles let the cart creep below s and then slip: 1 mm/s within 1 N of the static
  // model's force.
  const auto force = [](double t) { return 10.0 * t; };
  double at[2] = {0, 0};
  for (const bool presliding : {false, true}) {
    const CartRun run = Push("analytic", Cart(presliding), 4.0, force);
    int k = 0;
    while (k < run.qd.size() && run.qd[k] < 1e-3) ++k;
    ASSERT_LT(k, run.qd.size());
    at[presliding] = 10.0 * k * 1e-3;
    std::cout << "[measured] " << (presliding ? "LuGre" : "static") << ": 1 mm/s reached at " << at[presliding]
              << " N\n";
  }
  EXPECT_GT(at[0], kBreakaway);
  EXPECT_LT(at[0], kBreakaway + 2);
  EXPECT_NEAR(at[1], at[0], 1.0);
}

// The replay of a log is the simulation's inverse on a pre-sliding joint too (the
// contract's `replay`: the model's torques for the logged motion, its effects
// included): 40 N at 1 Hz drives the cart back and forth through its reversals, where
// its bristles take some 20 ms to turn the dry friction round (25 um of deflection at
// the cart's acceleration then). The log is written as the arm simulation writes one
// (sim/arm_simulation.cc): each row the state before a step, the force acting over it,
// the acceleration the step's own (the forward difference). Followed along the log
// (ArmFrictionAlong), the bristles give back the force the backend was given to
// rounding; the steady sliding formula flips the dry friction's sign at every reversal
// at once and misses by up to twice the friction level there. Measured (2026-12-04):
// LuGre and the Maxwell-slip element both within 1e-12 N; the steady formula 4.4 and
// 4.6 N RMS (largest 38 and 42 N).
TEST(PreslidingFriction, TheReplayFollowsTheBristlesAndGivesBackTheForceTheSimulationWasGiven) {
  const auto force = [](double t) { return 40.0 * std::sin(2 * 3.141592653589793 * t); };
  for (const bool maxwell : {false, true}) {
    const ArmModel m = Cart(true, maxwell);
    const CartRun run = Push("analytic", m, 2.0, force);
    const long n = run.q.size();  // rows 0..n-1: before steps 0..n-1; the last has no next row to difference
    ArmLog log;
    log.dof = 1;
    log.t = Eigen::VectorXd::LinSpaced(n, 0, (n - 1) * m.sample_time);
    log.q = Eigen::MatrixXd::Zero(n, 1);
    log.qd = Eigen::MatrixXd::Zero(n, 1);
    for (long k = 1; k < n; ++k) log.q(k, 0) = run.q[k - 1], log.qd(k, 0) = run.qd[k - 1];
    log.qdd = Eigen::MatrixXd(n, 1);
    log.tau = Eigen::MatrixXd(n, 1);
    for (long k = 0; k < n; ++k) {
      log.qdd(k, 0) = ((k + 1 < n ? run.qd[k] : log.qd(k, 0)) - log.qd(k, 0)) / m.sample_time;
      log.tau(k, 0) = force(static_cast<double>(k) * m.sample_time);
    }
    log.sample_period = m.sample_time;
    const ArmModel steady = Cart(false);  // the same friction without its bristles
    ASSERT_FALSE(steady.effects.joint(0).presliding());
    const Eigen::VectorXd followed = (PredictArmCommands(m, log).col(0) - log.tau.col(0)).head(n - 1);
    const Eigen::VectorXd sliding = (PredictArmCommands(steady, log).col(0) - log.tau.col(0)).head(n - 1);
    const double rms_followed = std::sqrt(followed.squaredNorm() / (n - 1)),
                 rms_sliding = std::sqrt(sliding.squaredNorm() / (n - 1));
    std::cout << "[measured] " << (maxwell ? "Maxwell-slip" : "LuGre") << ": replayed force off by " << rms_followed
              << " N RMS (largest " << followed.cwiseAbs().maxCoeff() << "), the steady formula's " << rms_sliding
              << " N (largest " << sliding.cwiseAbs().maxCoeff() << ")\n";
    EXPECT_GT(sliding.cwiseAbs().maxCoeff(), kSliding) << maxwell;
    EXPECT_LT(followed.cwiseAbs().maxCoeff(), 1e-6) << maxwell;
  }
}

TEST(PreslidingFriction, TheModelFileReadsWritesAndRefusesItsBristles) {
  ArmModel m = Cart(true);
  const std::vector<ArmEffect> listed = ListArmEffects(m.effects);
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].parameters.at("sigma0"), kSigma0);
  EXPECT_TRUE(m.effects.joint(0).presliding());
  ArmModel plain = Cart(false);
  EXPECT_EQ(ListArmEffects(plain.effects)[0].parameters.count("sigma0"), 0u);
  ArmEffects effects;
  EXPECT_THROW(AddArmEffect({"stribeck_friction", 0, {{"c", 1}, {"s", 2}, {"vs", 0.1}, {"sigma1", 5}}}, 1, &effects),
               InputError);
  EXPECT_THROW(AddArmEffect({"stribeck_friction", 0, {{"c", 1}, {"s", 2}, {"vs", 0.1}, {"sigma0", -5}}}, 1, &effects),
               InputError);
  EXPECT_THROW(AddArmEffect({"stribeck_friction", 0, {{"c", 1}, {"s", 2}, {"vs", 0.1}, {"maxwell", 1}}}, 1, &effects),
               InputError);
  EXPECT_THROW(
      AddArmEffect({"stribeck_friction", 0, {{"c", 1}, {"s", 2}, {"vs", 0.1}, {"sigma0", 5}, {"maxwell", 0.5}}}, 1,
                   &effects),
      InputError);
  const ArmModel maxwell = Cart(true, true);
  EXPECT_EQ(ListArmEffects(maxwell.effects)[0].parameters.at("maxwell"), 1.0);
  EXPECT_EQ(ListArmEffects(m.effects)[0].parameters.count("maxwell"), 0u);
}

}  // namespace
}  // namespace twinsim
