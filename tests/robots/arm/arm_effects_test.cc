// The arm effect vocabulary: each effect on its defining property, on every backend
// built (the effects act above the engines, so the numbers must agree), and the
// `effects:` list of a model file with its error messages.
#include "robots/arm/arm_effects.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iostream>

#include "analysis/arm_replay.h"
#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "sim/arm_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

using ::twinsim::testing::SourcePath;
using ::twinsim::testing::TempDir;
using ::twinsim::testing::WriteText;

// One link, 2 kg with its centre of mass 0.3 m out, on a joint whose axis is vertical
// (alpha 0: a turntable, gravity does nothing) or horizontal (alpha 90: a pendulum,
// hanging at q = -pi/2). Inertia about the axis J = 0.01 + 2 * 0.3^2 = 0.19 kg m^2.
constexpr double kJ = 0.19;       // kg m^2
constexpr double kMgl = 2 * 9.81 * 0.3;  // N·m

std::string OneLink(double alpha_deg, const std::string& effects = "") {
  return "robot: arm\nname: one\nsample_time: 0.001\ndh: modified\njoints:\n"
         "  - name: hinge\n    type: revolute\n    a: 0\n    alpha_deg: " +
         std::to_string(alpha_deg) +
         "\n    d: 0\n    theta_deg: 0\n    link:\n      mass: 2.0\n      com: [0.3, 0, 0]\n"
         "      inertia: [0.001, 0.01, 0.01, 0, 0, 0]\n" +
         (effects.empty() ? "" : "effects:\n" + effects);
}

ArmModel Turntable(const std::string& effects = "") {
  return LoadArmModelFromYamlString(OneLink(0, effects), "turntable.yaml");
}

ArmTrajectory Drive(const std::string& backend, const ArmModel& m, double q0, double qd0, double seconds,
                    const std::function<double(double)>& torque) {
  ArmSimulation sim(m, MakeArmBackend(backend, m));
  sim.Reset(Eigen::VectorXd::Constant(1, q0), Eigen::VectorXd::Constant(1, qd0));
  return sim.Run(static_cast<int>(std::lround(seconds / m.sample_time)) + 1,
                 [&](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
                   return Eigen::VectorXd::Constant(1, torque ? torque(t) : 0.0);
                 });
}

int Row(double t, double ts) { return static_cast<int>(std::lround(t / ts)); }

// The mean period (s) of x(t) - mean from its upward zero crossings (interpolated).
double Period(const Eigen::VectorXd& t, const Eigen::VectorXd& x) {
  const double mean = x.mean();
  std::vector<double> ups;
  for (int k = 1; k < x.size(); ++k) {
    const double a = x[k - 1] - mean, b = x[k] - mean;
    if (a < 0 && b >= 0) ups.push_back(t[k - 1] + (t[k] - t[k - 1]) * (-a) / (b - a));
  }
  if (ups.size() < 2) return NAN;
  return (ups.back() - ups.front()) / static_cast<double>(ups.size() - 1);
}

class ArmEffectsOnBackend : public ::testing::TestWithParam<std::string> {};

TEST_P(ArmEffectsOnBackend, PendulumSwingsWithTheSmallAnglePeriod) {
  // T = 2 pi sqrt(J / (m g l)); a 0.02 rad swing lengthens it by 2.5e-5.
  const ArmModel m = LoadArmModelFromYamlString(OneLink(90), "pendulum.yaml");
  const ArmTrajectory r = Drive(GetParam(), m, -kPi / 2 + 0.02, 0, 3.5, {});
  const double period = Period(r.t, r.q.col(0));
  const double expected = 2 * kPi * std::sqrt(kJ / kMgl);
  std::cout << "[measured] " << GetParam() << " pendulum period " << period << " s, closed form " << expected
            << " s\n";
  EXPECT_NEAR(period, expected, 1e-3 * expected);
}

TEST_P(ArmEffectsOnBackend, ViscousFrictionDecaysVelocityAtRateBOverJ) {
  const ArmModel m = Turntable("  - {name: viscous_friction, joint: 1, b: 0.38}\n");  // b / J = 2 /s
  const ArmTrajectory r = Drive(GetParam(), m, 0, 3.0, 1.0, {});
  for (double t : {0.25, 0.5, 1.0}) {
    // Measured: within 7e-7 of it (trapezoidal viscous friction at 1 ms).
    EXPECT_NEAR(r.qd(Row(t, 1e-3), 0), 3.0 * std::exp(-2 * t), 1e-5 * 3.0 * std::exp(-2 * t)) << "t = " << t;
  }
}

TEST_P(ArmEffectsOnBackend, CoulombFrictionDeceleratesByItsLevelPerDirectionAndSticks) {
  // c_pos / J = 2 rad/s^2, c_neg / J = 4 rad/s^2: from 2 rad/s the joint stops after
  // 1 s (1 rad) forwards, 0.5 s (0.5 rad) backwards, and then stays.
  const ArmModel m = Turntable("  - {name: coulomb_friction, joint: hinge, c_pos: 0.38, c_neg: 0.76}\n");
  // Measured: exact to 1e-15 on RK4; ode's steps lead by h qd0 / 2 = 1.25e-4 rad.
  const double q_tolerance = GetParam() == "ode" ? 2e-4 : 1e-12;
  const ArmTrajectory fwd = Drive(GetParam(), m, 0, 2.0, 1.5, {});
  EXPECT_NEAR(fwd.qd(Row(0.5, 1e-3), 0), 1.0, 1e-6);
  EXPECT_NEAR(fwd.q(Row(1.5, 1e-3), 0), 1.0, q_tolerance);
  EXPECT_LT(std::abs(fwd.qd(Row(1.5, 1e-3), 0)), 1e-9);
  EXPECT_EQ(fwd.q(Row(1.5, 1e-3), 0), fwd.q(Row(1.2, 1e-3), 0)) << "crept after stopping";
  const ArmTrajectory back = Drive(GetParam(), m, 0, -2.0, 1.0, {});
  EXPECT_NEAR(back.qd(Row(0.25, 1e-3), 0), -1.0, 1e-6);
  EXPECT_NEAR(back.q(Row(1.0, 1e-3), 0), -0.5, q_tolerance);
  EXPECT_LT(std::abs(back.qd(Row(1.0, 1e-3), 0)), 1e-9);
}

TEST_P(ArmEffectsOnBackend, StribeckFrictionBreaksAwayAtSAndSlidesAtC) {
  const ArmModel m = Turntable("  - {name: stribeck_friction, joint: 1, c: 0.2, s: 0.5, vs: 0.05}\n");
  // Below the static level it never starts.
  const ArmTrajectory held = Drive(GetParam(), m, 0, 0, 0.5, [](double) { return 0.48; });
  EXPECT_LT(held.q.col(0).cwiseAbs().maxCoeff(), 1e-12);  // ODE: 4e-13 of round-off
  // Above it, it breaks away and, well above vs, accelerates at (u - c) / J.
  const ArmTrajectory moving = Drive(GetParam(), m, 0, 0, 1.0, [](double) { return 0.52; });
  const double slope = (moving.qd(Row(1.0, 1e-3), 0) - moving.qd(Row(0.5, 1e-3), 0)) / 0.5;
  EXPECT_GT(moving.qd(Row(0.5, 1e-3), 0), 10 * 0.05);
  EXPECT_NEAR(slope, (0.52 - 0.2) / kJ, 1e-5 * (0.52 - 0.2) / kJ);  // measured 2e-7
}

TEST_P(ArmEffectsOnBackend, TorqueOffsetAndSaturationShapeWhatTheJointReceives) {
  // tau0 = 0.19 without a command: qdd = 1 rad/s^2, q(1) = 0.5.
  const ArmModel offset = Turntable("  - {name: torque_offset, joint: 1, tau0: 0.19}\n");
  const ArmTrajectory drifting = Drive(GetParam(), offset, 0, 0, 1.0, {});
  // ODE's semi-implicit Euler steps put q ahead by a h t / 2 (6e-5 rad here).
  const double q_tolerance = GetParam() == "ode" ? 1e-4 : 1e-6;
  EXPECT_NEAR(drifting.q(1000, 0), 0.5, q_tolerance);
  EXPECT_EQ(drifting.applied(10, 0), 0.19);
  // limit 0.38 on a command of +-5: the joint gets +-0.38 (qdd = +-2 rad/s^2).
  const ArmModel clipped = Turntable("  - {name: torque_saturation, joint: 1, limit: 0.38}\n");
  const ArmTrajectory r = Drive(GetParam(), clipped, 0, 0, 1.0, [](double t) { return t < 0.5 ? 5.0 : -5.0; });
  EXPECT_EQ(r.command(10, 0), 5.0);
  EXPECT_EQ(r.applied(10, 0), 0.38);
  EXPECT_EQ(r.applied(600, 0), -0.38);
  EXPECT_NEAR(r.qd(500, 0), 1.0, 1e-6);
  EXPECT_NEAR(r.qd(1000, 0), 0.0, 1e-6);
  EXPECT_NEAR(r.q(1000, 0), 0.5, q_tolerance);
}

TEST_P(ArmEffectsOnBackend, TimeDelayShiftsTheResponseByD) {
  auto step = [](double t) { return t >= 0.1 - 1e-12 ? 0.19 : 0.0; };  // qdd = 1 from t = 0.1 s
  const ArmTrajectory prompt = Drive(GetParam(), Turntable(), 0, 0, 0.6, step);
  // Whole samples: the delayed run is the prompt one, three samples later.
  const ArmTrajectory late = Drive(GetParam(), Turntable("  - {name: time_delay, joint: 1, delay: 0.003}\n"), 0, 0, 0.6, step);
  for (int k = 3; k < late.t.size(); ++k) ASSERT_NEAR(late.q(k, 0), prompt.q(k - 3, 0), 1e-12) << k;
  // A fraction of a sample: the impulse arrives d late, so q = (t - 0.1 - d)^2 / 2.
  const ArmTrajectory frac = Drive(GetParam(), Turntable("  - {name: time_delay, joint: 1, delay: 0.0025}\n"), 0, 0, 0.6, step);
  // (q: to 1.3e-7 from the impulse's spread over its sample, and ODE's h t / 2.)
  const double q_tolerance = GetParam() == "ode" ? 1e-4 : 1e-6;
  for (double t : {0.2, 0.6}) EXPECT_NEAR(frac.q(Row(t, 1e-3), 0), 0.5 * std::pow(t - 0.1025, 2), q_tolerance) << t;
  EXPECT_NEAR(frac.qd(Row(0.6, 1e-3), 0), 0.6 - 0.1025, 1e-8);
  // The same with four physics steps per sample: the delay then falls inside a step.
  ArmBackendOptions fine;
  fine.physics_substeps = 4;
  const ArmModel m = Turntable("  - {name: time_delay, joint: 1, delay: 0.0023}\n");
  ArmSimulation sim(m, MakeArmBackend(GetParam(), m, fine));
  EXPECT_EQ(sim.physics_substeps(), 4);
  const ArmTrajectory quarter = sim.Run(601, [&](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Eigen::VectorXd::Constant(1, step(t));
  });
  EXPECT_NEAR(quarter.qd(600, 0), 0.6 - 0.1023, 1e-8);
  EXPECT_NEAR(quarter.q(600, 0), 0.5 * std::pow(0.6 - 0.1023, 2), q_tolerance);
}

TEST_P(ArmEffectsOnBackend, JointFlexibilityResonatesAtSqrtKOverJeff) {
  // Motor inertia 0.05 and the link's 0.19 on a spring k = 1225 N·m/rad:
  // f = sqrt(k (1/J_m + 1/J_l)) / 2 pi = 28.0 Hz, the seed's mode.
  const ArmModel m = Turntable("  - {name: joint_flexibility, joint: 1, k: 1225, motor_inertia: 0.05}\n");
  const ArmTrajectory r = Drive(GetParam(), m, 0, 0, 0.5, [](double t) { return t < 0.001 ? 1.0 : 0.0; });
  const double f = 1 / Period(r.t.tail(450), r.qd.col(0).tail(450));
  const int window = static_cast<int>(std::lround(12 / f / 1e-3));  // 12 whole periods
  const double expected = std::sqrt(1225 * (1 / 0.05 + 1 / kJ)) / (2 * kPi);
  std::cout << "[measured] " << GetParam() << " joint_flexibility resonance " << f << " Hz, sqrt(k/J_eff) "
            << expected << " Hz\n";
  EXPECT_NEAR(f, expected, 0.01 * expected);
  // Momentum is shared: the link's mean speed is the impulse over both inertias.
  EXPECT_NEAR(r.qd.col(0).tail(window).mean(), 0.001 / (0.05 + kJ), 0.01 * 0.001 / (0.05 + kJ));
}

TEST_P(ArmEffectsOnBackend, TrapezoidalJointFlexibilityResonatesAtSqrtKOverJeff) {
  // The same turntable with the spring stepped by the trapezoidal rule
  // (`flexibility_integrator: trapezoidal`): h w = 0.18 at one step per sample, whose
  // resonance 2 atan(h w / 2) / h is 0.26 % low; and 4x stiffer, k = 4900 (h w = 0.35,
  // 2 steps per sample, 0.26 % low again).
  for (const double k : {1225.0, 4900.0}) {
    const std::string yaml =
        "flexibility_integrator: trapezoidal\n" +
        OneLink(0, "  - {name: joint_flexibility, joint: 1, k: " + std::to_string(k) + ", motor_inertia: 0.05}\n");
    const ArmModel m = LoadArmModelFromYamlString(yaml, "turntable.yaml");
    EXPECT_EQ(m.flexibility_integrator, FlexibilityIntegrator::kTrapezoidal);
    EXPECT_EQ(MakeArmBackend(GetParam(), m)->physics_substeps(), k < 2000 ? 1 : 2);
    const ArmTrajectory r = Drive(GetParam(), m, 0, 0, 0.5, [](double t) { return t < 0.001 ? 1.0 : 0.0; });
    const double f = 1 / Period(r.t.tail(450), r.qd.col(0).tail(450));
    const double expected = std::sqrt(k * (1 / 0.05 + 1 / kJ)) / (2 * kPi);
    std::cout << "[measured] " << GetParam() << " trapezoidal joint_flexibility k = " << k << ": resonance " << f
              << " Hz, sqrt(k/J_eff) " << expected << " Hz\n";
    EXPECT_NEAR(f, expected, 0.01 * expected);
    EXPECT_LT(f, expected);  // the trapezoidal rule's frequency warping
  }
}

TEST(ArmEffects, FlexibilityIntegratorIsReadWrittenAndCheckedWithItsLine) {
  EXPECT_EQ(Turntable().flexibility_integrator, FlexibilityIntegrator::kExplicit);
  const std::string dir = TempDir("arm_flex_integrator");
  const std::string path =
      WriteText(dir + "/arm.yaml", "flexibility_integrator: trapezoidal\n" +
                                       OneLink(0, "  - {name: joint_flexibility, joint: 1, k: 500, motor_inertia: 0.01}\n"));
  const ArmModel m = LoadArmModel(path);
  EXPECT_EQ(m.flexibility_integrator, FlexibilityIntegrator::kTrapezoidal);
  // Written back (as diagnose's model.yaml is) only when not the default.
  const std::string written = FormatArmModelYaml(m);
  EXPECT_NE(written.find("flexibility_integrator: trapezoidal"), std::string::npos) << written;
  EXPECT_EQ(LoadArmModelFromYamlString(written, "written.yaml").flexibility_integrator,
            FlexibilityIntegrator::kTrapezoidal);
  EXPECT_EQ(FormatArmModelYaml(Turntable()).find("flexibility_integrator"), std::string::npos);
  const std::string bad = WriteText(dir + "/bad.yaml", "flexibility_integrator: implicit\n" + OneLink(0));
  try {
    LoadArmModel(bad);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              bad + ":1:25: 'flexibility_integrator': unknown value 'implicit' (known: explicit, trapezoidal)");
  }
}

TEST_P(ArmEffectsOnBackend, PayloadIsHeldByItsOwnGravityTorque) {
  ArmModel m = LoadArmModel(SourcePath("models/rrr.yaml"));
  for (ArmJoint& j : m.joints) j.viscous = j.coulomb = 0;
  AddArmEffect(ArmEffect{"payload", -1, {{"mass", 0.8}, {"x", 0.35}}}, m.dof(), &m.effects);
  const Eigen::Vector3d q(0.2, 0.3, -0.4);
  const Eigen::VectorXd hold = InverseDynamics(ArmPlantModel(m), q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const Eigen::VectorXd nominal = InverseDynamics(m, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  auto run = [&](const Eigen::VectorXd& tau) {
    ArmSimulation sim(m, MakeArmBackend(GetParam(), m));
    sim.Reset(q, Eigen::Vector3d::Zero(), tau);
    return sim.Run(501, [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return tau; });
  };
  // Held by the torque that includes the payload, it stays.
  const ArmTrajectory held = run(hold);
  EXPECT_LT((held.q.bottomRows(1).transpose() - q).cwiseAbs().maxCoeff(), 1e-6);
  // Held by the nominal model's torque, it sags at M^-1 (nominal - hold).
  const ArmTrajectory sagging = run(nominal);
  const Eigen::VectorXd qdd = MassMatrix(ArmPlantModel(m), q).ldlt().solve(nominal - hold);
  const Eigen::VectorXd got = sagging.qd.row(10).transpose() / 0.010;
  EXPECT_LT((got - qdd).cwiseAbs().maxCoeff(), 0.01 * qdd.cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(Built, ArmEffectsOnBackend, ::testing::ValuesIn(AvailableArmEngines()),
                         [](const auto& info) { return info.param; });

TEST(ArmEffects, PayloadChangesTheGravityTorqueByMGL) {
  // The RRR arm stretched out horizontally: the shoulder holds the payload at 0.40 m
  // (the last link's frame sits on the elbow axis) or 0.75 m (x = 0.35: at the tool).
  const ArmModel m = LoadArmModel(SourcePath("models/rrr.yaml"));
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Eigen::VectorXd bare = InverseDynamics(m, zero, zero, zero, false);
  for (double x : {0.0, 0.35}) {
    ArmModel loaded = m;
    AddArmEffect(ArmEffect{"payload", -1, {{"mass", 0.5}, {"x", x}}}, m.dof(), &loaded.effects);
    const Eigen::VectorXd diff = InverseDynamics(ArmPlantModel(loaded), zero, zero, zero, false) - bare;
    EXPECT_NEAR(diff[0], 0, 1e-12);
    EXPECT_NEAR(diff[1], 0.5 * 9.81 * (0.40 + x), 1e-12) << "x = " << x;
    EXPECT_NEAR(diff[2], 0.5 * 9.81 * x, 1e-12) << "x = " << x;
    EXPECT_EQ(ArmPlantModel(loaded).effects.payload_mass, 0.0);
  }
}

TEST(ArmEffects, FrictionHoldsAStuckArmExactlyStill) {
  // The RRR arm's own Coulomb friction (1.5, 1.0, 0.5 N·m) holds it against a push
  // below those levels on top of gravity compensation: no creep, no chatter.
  const ArmModel m = LoadArmModel(SourcePath("models/rrr.yaml"));
  const Eigen::Vector3d q(0.2, 0.3, -0.4), push(1.2, -0.8, 0.4);
  for (const std::string& backend : AvailableArmEngines()) {
    ArmSimulation sim(m, MakeArmBackend(backend, m));
    const Eigen::VectorXd tau = InverseDynamics(m, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), false) + push;
    sim.Reset(q, Eigen::Vector3d::Zero(), tau);
    const ArmTrajectory r = sim.Run(1001, [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return tau; });
    EXPECT_LT((r.q.bottomRows(1).transpose() - q).cwiseAbs().maxCoeff(), 1e-7) << backend;
    EXPECT_LT(r.qd.cwiseAbs().maxCoeff(), 1e-6) << backend;
  }
}

TEST(ArmEffects, ModelFileEffectsRoundTripThroughTheList) {
  const ArmModel m = Turntable(
      "  - {name: viscous_friction, joint: 1, b: 0.1}\n"
      "  - {name: coulomb_friction, joint: hinge, c: 0.3}\n"
      "  - {name: position_friction, joint: 1, from: -1, to: 1, c1: 0.2, c2: 0, c3: 0.1}\n"
      "  - {name: stribeck_friction, joint: 1, c: 0.1, s: 0.2, vs: 0.01}\n"
      "  - {name: torque_offset, joint: 1, tau0: -0.05}\n"
      "  - {name: position_torque, joint: 1, from: 0, to: 2, p1: 0.3, p2: -0.1}\n"
      "  - {name: torque_saturation, joint: 1, limit: 4}\n"
      "  - {name: time_delay, joint: 1, delay: 0.002}\n"
      "  - {name: joint_flexibility, joint: 1, k: 500, damping: 0.2, motor_inertia: 0.01}\n"
      "  - {name: payload, joint: null, mass: 0.3}\n");
  const JointEffects e = m.effects.joint(0);
  EXPECT_EQ(e.viscous, 0.1);
  EXPECT_EQ(e.coulomb_positive, 0.3);
  EXPECT_EQ(e.coulomb_negative, 0.3);
  EXPECT_EQ(e.stribeck_static, 0.2);
  EXPECT_EQ(e.time_delay, 0.002);
  EXPECT_EQ(e.flex_damping, 0.2);
  EXPECT_EQ(m.effects.payload_mass, 0.3);
  EXPECT_EQ(e.friction_profile.knots, 3);
  EXPECT_EQ(e.friction_profile.levels[2], 0.1);
  const std::vector<ArmEffect> list = ListArmEffects(m.effects);
  ASSERT_EQ(list.size(), 10u);
  std::vector<std::string> names;
  for (const ArmEffect& fx : list) names.push_back(fx.name);
  // Each joint's effects in the vocabulary's order, position_friction beside the other
  // dry friction, position_torque beside the offset; the payload last.
  EXPECT_EQ(names, (std::vector<std::string>{"viscous_friction", "coulomb_friction", "position_friction",
                                             "stribeck_friction", "torque_offset", "position_torque",
                                             "torque_saturation", "time_delay", "joint_flexibility", "payload"}));
  std::vector<std::string> vocabulary = ArmEffectNames();
  std::sort(vocabulary.begin(), vocabulary.end());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, vocabulary);
  ArmEffects rebuilt;
  for (const ArmEffect& fx : list) AddArmEffect(fx, 1, &rebuilt);
  EXPECT_EQ(ListArmEffects(rebuilt).size(), 10u);
  EXPECT_EQ(rebuilt.joint(0).torque_profile.levels[1], -0.1);
  EXPECT_EQ(rebuilt.joint(0).friction_profile.levels[0], 0.2);
  EXPECT_EQ(rebuilt.joint(0).stiffness, 500);
  EXPECT_EQ(rebuilt.payload_mass, 0.3);
  // The friction torque of the model: nominal (none here) plus all three laws.
  EXPECT_NEAR(ArmFrictionTorque(m, 0, 0.0, 2.0), 0.1 * 2 + 0.3 + 0.1 + 0.1 * std::exp(-40000.0), 1e-12);
  EXPECT_NEAR(ArmFrictionTorque(m, 0, 0.0, -0.01), -0.001 - 0.3 - (0.1 + 0.1 * std::exp(-1.0)), 1e-12);
  EXPECT_EQ(ArmFrictionTorque(m, 0, 0.0, 0.0), 0);
}

TEST(ArmEffects, PositionFrictionInterpolatesItsKnotsAndHoldsTheEndsBeyondThem) {
  const ArmModel m = Turntable(
      "  - {name: coulomb_friction, joint: 1, c: 0.1}\n"
      "  - {name: position_friction, joint: 1, from: -1, to: 1, c1: 0.4, c2: 0, c3: 0.2}\n");
  const JointEffects e = m.effects.joint(0);
  ASSERT_EQ(e.friction_profile.knots, 3);
  // Knots at -1, 0 and 1; linear between; the end levels beyond them.
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(-1), 0.4);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(-0.25), 0.1);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(0), 0);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(0.5), 0.1);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(1), 0.2);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(-7), 0.4);
  EXPECT_DOUBLE_EQ(e.PositionFrictionLevel(7), 0.2);
  // It adds to the joint's other dry friction and opposes the motion either way.
  const double nominal = m.joints[0].coulomb, viscous = m.joints[0].viscous;
  EXPECT_NEAR(ArmFrictionTorque(m, 0, -0.25, 2.0), viscous * 2 + nominal + 0.1 + 0.1, 1e-12);
  EXPECT_NEAR(ArmFrictionTorque(m, 0, 0.5, -2.0), -viscous * 2 - nominal - 0.1 - 0.1, 1e-12);
  EXPECT_NEAR(ArmDryFrictionLevel(m, 0, -1, 0), nominal + 0.1 + 0.4, 1e-12);
}

TEST(ArmEffects, PositionFrictionHoldsAJointWhereItsLevelExceedsThePushOnEveryEngine) {
  // The turntable (no gravity on it, no other friction) pushed by a constant torque
  // u = 0.1 N·m against a level c(q) = 0.2 q: where the level exceeds the push the joint
  // stays put. Started at rest at q0 = 0.1, where it is below, it swings about q = 0.5
  // (I q'' = u - c(q), a harmonic oscillator) and comes to rest at the far end of the
  // swing, q = 0.9, where the work u (q - q0) equals the friction's 0.1 (q^2 - q0^2) and
  // the level (0.18) holds it: on every engine alike.
  const ArmModel m = Turntable("  - {name: position_friction, joint: 1, from: 0, to: 1, c1: 0, c2: 0.2}\n");
  ASSERT_EQ(m.joints[0].coulomb, 0);
  ASSERT_EQ(m.joints[0].viscous, 0);
  const double push = 0.1;
  for (const std::string& backend : AvailableArmEngines()) {
    ArmSimulation held(m, MakeArmBackend(backend, m));
    held.Reset(Eigen::VectorXd::Constant(1, 0.8), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, push));
    const ArmTrajectory still = held.Run(
        501, [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return Eigen::VectorXd::Constant(1, push); });
    EXPECT_LT(std::abs(still.q(still.q.rows() - 1, 0) - 0.8), 1e-9) << backend << ": it crept where the level holds it";

    ArmSimulation sliding(m, MakeArmBackend(backend, m));
    sliding.Reset(Eigen::VectorXd::Constant(1, 0.1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, push));
    const ArmTrajectory run = sliding.Run(
        4001, [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return Eigen::VectorXd::Constant(1, push); });
    EXPECT_NEAR(run.q(run.q.rows() - 1, 0), 0.9, 2e-3) << backend << ": not where the work balances";
    EXPECT_LT(std::abs(run.qd(run.qd.rows() - 1, 0)), 1e-9) << backend << ": it has not come to rest";
  }
}

TEST(ArmEffects, PositionTorqueIsASpringWhenItFallsAlongTheTravelOnEveryEngineAndInTheReplay) {
  // p(q) through p1 = 0.2 at q = -1 and p2 = -0.2 at q = 1 is the spring p = -k q with
  // k = 0.2 N·m/rad: the frictionless turntable released at q0 = 0.5 swings as
  // q0 cos(w t), w = sqrt(k / J), its amplitude kept (no friction to take its energy).
  const ArmModel m = Turntable("  - {name: position_torque, joint: 1, from: -1, to: 1, p1: 0.2, p2: -0.2}\n");
  const JointEffects e = m.effects.joint(0);
  ASSERT_TRUE(e.torque_profile.on());
  EXPECT_DOUBLE_EQ(e.PositionTorque(0.5), -0.1);
  EXPECT_DOUBLE_EQ(e.PositionTorque(-3), 0.2) << "the end level beyond the last knot";
  const double k = 0.2, w = std::sqrt(k / kJ), q0 = 0.5;
  for (const std::string& backend : AvailableArmEngines()) {
    const ArmTrajectory r = Drive(backend, m, q0, 0, 13, nullptr);
    EXPECT_NEAR(Period(r.t, r.q.col(0)), 2 * kPi / w, 2e-3 * 2 * kPi / w) << backend;
    const int last_period = Row(13 - 2 * kPi / w, m.sample_time);
    const Eigen::VectorXd tail = r.q.col(0).tail(r.q.rows() - last_period);
    EXPECT_NEAR(tail.maxCoeff(), q0, 5e-3) << backend << ": the swing lost or gained energy";
    EXPECT_NEAR(tail.minCoeff(), -q0, 5e-3) << backend;
  }
  // The replay: the closed-form swing needs no command with the spring in the model, and
  // J q'' = -k q without it.
  ArmLog log;
  log.dof = 1;
  const int rows = 2001;
  log.t = Eigen::VectorXd::LinSpaced(rows, 0, 2);
  log.q = (q0 * (w * log.t.array()).cos()).matrix();
  log.qd = (-q0 * w * (w * log.t.array()).sin()).matrix();
  log.qdd = (-q0 * w * w * (w * log.t.array()).cos()).matrix();
  log.tau = Eigen::MatrixXd::Zero(rows, 1);
  log.sample_period = 1e-3;
  EXPECT_LT(PredictArmCommands(m, log).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd without = PredictArmCommands(Turntable(), log);
  EXPECT_LT((without + k * log.q).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ArmEffects, BadEffectsAreRefusedWithFileLineAndTheKnownNames) {
  const std::string dir = TempDir("arm_effects");
  auto error_of = [&](const std::string& effects) -> std::string {
    const std::string path = WriteText(dir + "/arm.yaml", OneLink(0, effects));
    try {
      LoadArmModel(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string path = dir + "/arm.yaml";
  // The effects list starts on line 17 of OneLink's text.
  EXPECT_EQ(error_of("  - {name: viscosity, joint: 1, b: 0.1}\n"),
            path + ":17:12: 'name' in 'effect 1': unknown value 'viscosity' (known: viscous_friction, coulomb_friction, "
                   "stribeck_friction, torque_offset, torque_saturation, time_delay, joint_flexibility, payload, "
                   "position_friction, position_torque)");
  EXPECT_EQ(error_of("  - {name: viscous_friction, joint: 1, b: 0.1}\n  - {name: viscous_friction, joint: 1, bb: 1}\n"),
            path + ":18:5: missing required key 'b' in 'effect 2'\n" + path +
                ":18:40: unknown key 'bb' in 'effect 2' (known: b, joint, name)");
  EXPECT_EQ(error_of("  - {name: viscous_friction, joint: 1, b: -0.1}\n"),
            path + ":17:43: 'b' in 'effect 1': must not be negative, got -0.1");
  EXPECT_EQ(error_of("  - {name: viscous_friction, joint: wrist, b: 0.1}\n"),
            path + ":17:37: 'joint' in 'effect 1': no joint 'wrist' (known: 1..1 or hinge)");
  EXPECT_EQ(error_of("  - {name: viscous_friction, joint: 2, b: 0.1}\n"),
            path + ":17:37: 'joint' in 'effect 1': no joint '2' (known: 1..1 or hinge)");
  EXPECT_EQ(error_of("  - {name: torque_offset, tau0: 0.1}\n"), path + ":17:5: missing required key 'joint' in 'effect 1'");
  EXPECT_EQ(error_of("  - {name: payload, joint: 1, mass: 0.1}\n"),
            path + ":17:5: effect 1: effect 'payload' acts on the last link: its joint must be null");
  EXPECT_EQ(error_of("  - {name: stribeck_friction, joint: 1, c: 0.3, s: 0.2, vs: 0.01}\n"),
            path + ":17:5: effect 1: effect 'stribeck_friction': the static level s = 0.2 must exceed the sliding "
                   "level c = 0.3");
  EXPECT_EQ(error_of("  - {name: coulomb_friction, joint: 1, c_pos: 0.3}\n"),
            path + ":17:5: effect 1: effect 'coulomb_friction': needs 'c' (both directions) or both 'c_pos' and "
                   "'c_neg'");
  EXPECT_EQ(error_of("  - {name: time_delay, joint: 1, delay: 0.01}\n  - {name: time_delay, joint: hinge, delay: 0.02}\n"),
            path + ":18:5: effect 2: effect 'time_delay' given twice for joint 1");
  EXPECT_EQ(error_of("  - {name: position_friction, joint: 1, from: 0.5, to: 0.5, c1: 0.1, c2: 0.2}\n"),
            path + ":17:5: effect 1: effect 'position_friction': the last knot 'to' = 0.5 must lie beyond the first, "
                   "'from' = 0.5");
  EXPECT_EQ(error_of("  - {name: position_friction, joint: 1, from: 0, to: 1, c1: 0.1, c2: 0.2, c4: 0.3}\n"),
            path + ":17:5: effect 1: effect 'position_friction': 'c4' given without 'c3': the levels are c1, c2, ... "
                   "in order");
  EXPECT_EQ(error_of("  - {name: position_friction, joint: 1, from: 0, to: 1, c1: 0.1}\n"),
            path + ":17:5: missing required key 'c2' in 'effect 1'");
  // A level may take away from the joint's Coulomb friction, not more.
  EXPECT_EQ(error_of("  - {name: position_friction, joint: 1, from: 0, to: 1, c1: 0.1, c2: -0.2}\n"),
            path + ": joint 1 'hinge': its dry friction would be -0.2 at position_friction's knot 2 (the joint's "
                   "Coulomb friction plus c2): it must not be negative");
  EXPECT_EQ(error_of("  - {name: coulomb_friction, joint: 1, c: 0.3}\n"
                     "  - {name: position_friction, joint: 1, from: 0, to: 1, c1: 0.1, c2: -0.2}\n"),
            "no error");
  EXPECT_EQ(error_of("  - {name: position_torque, joint: 1, from: 1, to: 0, p1: 0.1, p2: 0.2}\n"),
            path + ":17:5: effect 1: effect 'position_torque': the last knot 'to' = 0 must lie beyond the first, "
                   "'from' = 1");
  EXPECT_EQ(error_of("  - {name: position_torque, joint: 1, from: 0, to: 1, p1: 0.1, p2: 0.2, p5: 0.3}\n"),
            path + ":17:5: effect 1: effect 'position_torque': 'p5' given without 'p3': the levels are p1, p2, ... "
                   "in order");
  EXPECT_EQ(error_of("  - {name: position_torque, joint: 1, from: 0, to: 1, p1: 0.1, p2: 0.2, c3: 0.3}\n"),
            path + ":17:73: unknown key 'c3' in 'effect 1' (known: from, joint, name, p1, p10, p11, p12, p2, p3, p4, "
                   "p5, p6, p7, p8, p9, to)");
  EXPECT_EQ(error_of("  name: viscous_friction\n"), path + ":17:3: 'effects': expected a list of effects, each with a 'name'");
  // Programmatic additions say the same without a place.
  ArmEffects fx;
  try {
    AddArmEffect(ArmEffect{"joint_flexibility", 0, {{"k", 100}, {"stiffness", 1}}}, 1, &fx);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "effect 'joint_flexibility': unknown parameter 'stiffness' (known: k, damping, motor_inertia)\n"
                 "effect 'joint_flexibility': missing parameter 'motor_inertia'");
  }
  EXPECT_FALSE(fx.any()) << "a refused effect left something behind";
  EXPECT_THROW(AddArmEffect(ArmEffect{"backlash", 0, {}}, 1, &fx), InputError);
}

}  // namespace
}  // namespace twinsim
