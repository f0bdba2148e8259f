// Arm dynamics against closed forms and against each other: Newton-Euler, the mass
// matrix, the articulated-body and composite-rigid-body algorithms against their
// Newton-Euler references, the integrators, the regressor, energy, base parameters.
#include "robots/arm/arm_dynamics.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>

#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_integrators.h"
#include "robots/arm/arm_regressor.h"
#include "robots/arm/arm_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A random serial chain: random joint placements, axes, types, masses and inertias.
ArmModel RandomArm(int n, std::uint64_t seed, bool with_prismatic) {
  Rng rng(seed);
  ArmModel m;
  m.name = "random";
  for (int i = 0; i < n; ++i) {
    ArmJoint j;
    j.name = "j" + std::to_string(i + 1);
    j.type = with_prismatic && i == 1 ? JointType::kPrismatic : JointType::kRevolute;
    j.origin = Eigen::Isometry3d::Identity();
    j.origin.translate(Eigen::Vector3d(rng.Uniform(-0.3, 0.3), rng.Uniform(-0.3, 0.3), rng.Uniform(0, 0.4)));
    j.origin.rotate(Eigen::AngleAxisd(rng.Uniform(-3, 3), Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized()));
    j.axis = Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
    j.child.mass = rng.Uniform(0.5, 5);
    j.child.com = Eigen::Vector3d(rng.Uniform(-0.2, 0.2), rng.Uniform(-0.2, 0.2), rng.Uniform(-0.2, 0.2));
    // A physical inertia: a random box's, rotated.
    const Eigen::Vector3d s(rng.Uniform(0.05, 0.4), rng.Uniform(0.05, 0.4), rng.Uniform(0.05, 0.4));
    const Eigen::Vector3d d = j.child.mass / 12.0 *
                              Eigen::Vector3d(s.y() * s.y() + s.z() * s.z(), s.x() * s.x() + s.z() * s.z(), s.x() * s.x() + s.y() * s.y());
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(rng.Uniform(-3, 3), Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    j.child.inertia = rot * d.asDiagonal() * rot.transpose();
    j.viscous = rng.Uniform(0, 1);
    j.coulomb = rng.Uniform(0, 2);
    m.joints.push_back(j);
  }
  return m;
}

Eigen::VectorXd RandomVector(int n, Rng* rng, double scale) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = rng->Uniform(-scale, scale);
  return v;
}

TEST(ArmDynamics, PendulumMatchesTheClosedForm) {
  // One link about a horizontal axis (y), centre of mass l along x:
  // tau = (I_yy + m l^2) qdd - m g l cos(q).
  ArmModel m;
  ArmJoint j;
  j.axis = Eigen::Vector3d::UnitY();
  j.child.mass = 2.0;
  j.child.com = Eigen::Vector3d(0.3, 0, 0);
  j.child.inertia = Eigen::Vector3d(0.01, 0.02, 0.03).asDiagonal();
  m.joints.push_back(j);
  Rng rng(1);
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd q(1), qd(1), qdd(1);
    q << rng.Uniform(-3, 3);
    qd << rng.Uniform(-3, 3);
    qdd << rng.Uniform(-5, 5);
    const double expected = (0.02 + 2.0 * 0.09) * qdd[0] - 2.0 * 9.81 * 0.3 * std::cos(q[0]);
    EXPECT_NEAR(InverseDynamics(m, q, qd, qdd, false)[0], expected, 1e-12);
  }
}

TEST(ArmDynamics, NewtonEulerEqualsMassMatrixPlusBias) {
  for (bool prismatic : {false, true}) {
    const ArmModel m = RandomArm(7, 3, prismatic);
    Rng rng(5);
    for (int k = 0; k < 10; ++k) {
      const Eigen::VectorXd q = RandomVector(7, &rng, 3), qd = RandomVector(7, &rng, 2), qdd = RandomVector(7, &rng, 5);
      const Eigen::MatrixXd mass = MassMatrix(m, q);
      EXPECT_TRUE((InverseDynamics(m, q, qd, qdd, false) - (mass * qdd + BiasForces(m, q, qd))).norm() < 1e-9);
      // M is symmetric positive definite, and forward dynamics inverts inverse dynamics.
      EXPECT_GT(mass.llt().matrixL().toDenseMatrix().diagonal().minCoeff(), 0);
      const Eigen::VectorXd tau = InverseDynamics(m, q, qd, qdd, true);
      EXPECT_LT((ForwardDynamics(m, q, qd, tau, true) - qdd).norm(), 1e-8);
    }
  }
}

TEST(ArmDynamics, RegressorTimesParametersIsTheTorque) {
  for (bool prismatic : {false, true}) {
    const ArmModel m = RandomArm(6, 7, prismatic);
    const Eigen::VectorXd pi = StandardParameters(m);
    Rng rng(9);
    for (int k = 0; k < 10; ++k) {
      const Eigen::VectorXd q = RandomVector(6, &rng, 3), qd = RandomVector(6, &rng, 2), qdd = RandomVector(6, &rng, 5);
      EXPECT_LT((Regressor(m, q, qd, qdd) * pi - InverseDynamics(m, q, qd, qdd, true)).norm(), 1e-9);
    }
    // And the parameters map back to the same model.
    const ArmModel back = WithStandardParameters(m, pi);
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR((back.joints[i].child.com - m.joints[i].child.com).norm(), 0, 1e-12);
      EXPECT_NEAR((back.joints[i].child.inertia - m.joints[i].child.inertia).norm(), 0, 1e-12);
    }
  }
}

TEST(ArmDynamics, FreeSwingConservesEnergy) {
  ArmModel m = RandomArm(3, 11, false);
  for (auto& j : m.joints) j.viscous = j.coulomb = 0;
  Eigen::VectorXd q = Eigen::VectorXd::Constant(3, 0.3), qd = Eigen::VectorXd::Zero(3);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(3);
  const double e0 = KineticEnergy(m, q, qd) + PotentialEnergy(m, q);
  const double dt = 1e-3;
  for (int k = 0; k < 2000; ++k) {  // RK4, 2 s
    auto f = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv) { return ForwardDynamics(m, qq, vv, tau, false); };
    const Eigen::VectorXd a1 = f(q, qd);
    const Eigen::VectorXd a2 = f(q + 0.5 * dt * qd, qd + 0.5 * dt * a1);
    const Eigen::VectorXd a3 = f(q + 0.5 * dt * (qd + 0.5 * dt * a1), qd + 0.5 * dt * a2);
    const Eigen::VectorXd a4 = f(q + dt * (qd + 0.5 * dt * a2), qd + dt * a3);
    q += dt * qd + dt * dt / 6 * (a1 + a2 + a3);
    qd += dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
  }
  const double e1 = KineticEnergy(m, q, qd) + PotentialEnergy(m, q);
  EXPECT_GT(KineticEnergy(m, q, qd), 0.01) << "it should be swinging";
  EXPECT_NEAR(e1, e0, 1e-6 * std::abs(e0) + 1e-7);
}

TEST(ArmBaseParameters, PlanarTwoLinkArmInAVerticalPlaneHasSixInertialBaseParameters) {
  // Two parallel horizontal axes (Khalil & Dombre): ZZR1, MXR1, MY1, ZZ2, MX2, MY2, plus
  // viscous and Coulomb friction on both joints.
  ArmModel m;
  for (int i = 0; i < 2; ++i) {
    ArmJoint j;
    j.axis = Eigen::Vector3d::UnitZ();
    j.origin = Eigen::Isometry3d::Identity();
    if (i == 0) j.origin.rotate(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()));  // horizontal axis
    else j.origin.translate(Eigen::Vector3d(0.4, 0, 0));
    j.child.mass = 1.0 + i;
    j.child.com = Eigen::Vector3d(0.2, 0.01, 0.02);
    j.child.inertia = Eigen::Vector3d(0.01, 0.02, 0.03).asDiagonal();
    m.joints.push_back(j);
  }
  const BaseParameters base = FindBaseParameters(m);
  EXPECT_EQ(base.rank(), 6 + 4);
  // The base parameters reproduce every torque.
  const Eigen::VectorXd pi = StandardParameters(m);
  const Eigen::VectorXd beta = base.from_standard * pi;
  Rng rng(2);
  for (int k = 0; k < 10; ++k) {
    const Eigen::VectorXd q = RandomVector(2, &rng, 3), qd = RandomVector(2, &rng, 2), qdd = RandomVector(2, &rng, 5);
    const Eigen::MatrixXd y = Regressor(m, q, qd, qdd);
    EXPECT_LT((base.Reduce(y) * beta - y * pi).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace twinsim

namespace twinsim {
namespace {

TEST(ArmBaseParameters, TheRrrArmHasFifteenInertialBaseParameters) {
  // Seed 001 section III: the RRR arm's dynamics depend on 15 combinations of its
  // inertial parameters; with viscous and Coulomb friction on each joint, 21 in all.
  const ArmModel m = LoadArmModel(std::string(TWINSIM_SOURCE_DIR) + "/models/rrr.yaml");
  const BaseParameters base = FindBaseParameters(m);
  EXPECT_EQ(base.rank(), 15 + 6);
  // Three parallel-axis regroupings of the textbook (Khalil & Dombre) with a2 = 0.4 m:
  // m3 joins the shoulder's first moment and, times a2^2, its inertias.
  const Eigen::VectorXd beta = base.from_standard * StandardParameters(m);
  bool found = false;
  for (int k = 0; k < base.rank(); ++k)
    if (base.names[static_cast<std::size_t>(k)].rfind("mcx2 + 0.4 m3", 0) == 0) {
      found = true;
      EXPECT_NEAR(beta[k], m.joints[1].child.mass * m.joints[1].child.com.x() + 0.4 * m.joints[2].child.mass, 1e-9);
    }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace twinsim

namespace twinsim {
namespace {

// The arms the fast algorithms are checked on: random 7-joint chains with and without a
// prismatic joint, an all-prismatic chain, the RRR arm with a payload, and the KUKA
// LWR4 of ../shared/realdata when it is there.
std::vector<ArmModel> TestArms() {
  std::vector<ArmModel> arms = {RandomArm(7, 3, false), RandomArm(7, 13, true)};
  ArmModel sliders = RandomArm(4, 17, false);
  for (auto& j : sliders.joints) j.type = JointType::kPrismatic;
  arms.push_back(sliders);
  ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  AddArmEffect(ArmEffect{"payload", -1, {{"mass", 1.5}, {"x", 0.05}, {"y", 0.02}, {"z", -0.03}}}, rrr.dof(),
               &rrr.effects);
  arms.push_back(ArmPlantModel(rrr));
  const std::string kuka = testing::SourcePath("../shared/realdata/kuka_lwr4/kuka_lwr4.urdf");
  if (std::filesystem::exists(kuka)) arms.push_back(LoadArmModel(kuka));
  return arms;
}

TEST(ArmDynamics, ArticulatedBodyMatchesTheNewtonEulerReference) {
  // 1e-10 relative: both are exact up to rounding, which the reference's Cholesky
  // solve multiplies by M's condition number (about 1e3 for the KUKA's light wrist).
  for (const ArmModel& m : TestArms()) {
    const int n = m.dof();
    Rng rng(21);
    for (int k = 0; k < 50; ++k) {
      const Eigen::VectorXd q = RandomVector(n, &rng, 3), qd = RandomVector(n, &rng, 2),
                            tau = RandomVector(n, &rng, 20);
      for (bool friction : {false, true}) {
        const Eigen::VectorXd fast = ForwardDynamics(m, q, qd, tau, friction);
        const Eigen::VectorXd reference = ForwardDynamicsReference(m, q, qd, tau, friction);
        EXPECT_LE((fast - reference).norm(), 1e-10 * reference.norm()) << m.name << " state " << k;
      }
    }
  }
}

TEST(ArmDynamics, ArticulatedBodyInvertsInverseDynamics) {
  for (const ArmModel& m : TestArms()) {
    const int n = m.dof();
    Rng rng(23);
    Eigen::VectorXd qdd;
    for (int k = 0; k < 20; ++k) {
      const Eigen::VectorXd q = RandomVector(n, &rng, 3), qd = RandomVector(n, &rng, 2),
                            expected = RandomVector(n, &rng, 5);
      ForwardDynamics(m, q, qd, InverseDynamics(m, q, qd, expected, true), true, &qdd);
      EXPECT_LE((qdd - expected).norm(), 1e-10 * expected.norm()) << m.name;
    }
  }
}

TEST(ArmDynamics, CompositeRigidBodyAndBiasMatchTheNewtonEulerReference) {
  for (const ArmModel& m : TestArms()) {
    Rng rng(25);
    for (int k = 0; k < 20; ++k) {
      const Eigen::VectorXd q = RandomVector(m.dof(), &rng, 3);
      const Eigen::MatrixXd fast = MassMatrix(m, q), reference = MassMatrixReference(m, q);
      EXPECT_LE((fast - reference).norm(), 1e-12 * reference.norm()) << m.name;
      EXPECT_EQ((fast - fast.transpose()).norm(), 0) << "symmetric by construction";
      // And with the bias forces of the same pass.
      const Eigen::VectorXd qd = RandomVector(m.dof(), &rng, 2);
      Eigen::MatrixXd mass;
      Eigen::VectorXd bias;
      MassMatrixAndBias(m, q, qd, &mass, &bias);
      EXPECT_EQ((mass - fast).norm(), 0);
      const Eigen::VectorXd bias_reference = BiasForces(m, q, qd);
      EXPECT_LE((bias - bias_reference).norm(), 1e-12 * bias_reference.norm()) << m.name;
    }
  }
}

TEST(ArmDynamics, PrismaticJointsMatchTheClosedForm) {
  // A vertical slider carrying a horizontal one: m_total qdd1 = tau1 - m_total g, and
  // the second, horizontal, feels no gravity: m2 qdd2 = tau2.
  const ArmModel m = LoadArmModelFromYamlString(R"(
robot: arm
name: sliders
joints:
  - {name: lift, type: prismatic, origin: {xyz: [0, 0, 0.1], rpy: [0, 0, 0]}, axis: [0, 0, 1],
     link: {mass: 3, com: [0.1, 0, 0], inertia: [0.01, 0.02, 0.03, 0, 0, 0]}}
  - {name: reach, type: prismatic, origin: {xyz: [0.2, 0, 0], rpy: [0, 0, 0]}, axis: [1, 0, 0],
     link: {mass: 2, com: [0, 0.05, 0], inertia: [0.01, 0.01, 0.01, 0, 0, 0]}}
)", "sliders");
  Rng rng(27);
  for (int k = 0; k < 10; ++k) {
    const Eigen::VectorXd q = RandomVector(2, &rng, 0.5), qd = RandomVector(2, &rng, 1), tau = RandomVector(2, &rng, 50);
    const Eigen::VectorXd qdd = ForwardDynamics(m, q, qd, tau, false);
    EXPECT_NEAR(qdd[0], tau[0] / 5 - 9.81, 1e-12);
    EXPECT_NEAR(qdd[1], tau[1] / 2, 1e-12);
  }
}

TEST(ArmDynamics, Rk4IsFourthOrderAndSemiImplicitEulerFirstOrder) {
  // The global error after 0.5 s of swing against a 0.05 ms RK4 reference falls by 2^4
  // when RK4's step halves and by 2 when semi-implicit Euler's does. Without friction:
  // Coulomb's sign(qd) is not smooth, and neither method keeps its order across it.
  const ArmModel m = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const Eigen::VectorXd q0 = Eigen::Vector3d(0.2, 0.4, -0.6), tau = Eigen::Vector3d(1, 2, -1);
  auto run = [&](double h, bool rk4) {
    Eigen::VectorXd q = q0, qd = Eigen::Vector3d(1, -0.5, 0.8);
    ArmStepWorkspace work;
    for (int k = 0; k < static_cast<int>(std::lround(0.5 / h)); ++k) {
      if (rk4) Rk4Step(m, tau, h, false, &work, &q, &qd);
      else SemiImplicitEulerStep(m, tau, h, false, &work, &q, &qd);
    }
    return q;
  };
  const Eigen::VectorXd reference = run(5e-5, true);
  const double rk4_coarse = (run(4e-3, true) - reference).norm(), rk4_fine = (run(2e-3, true) - reference).norm();
  EXPECT_NEAR(rk4_coarse / rk4_fine, 16, 3);
  const double euler_coarse = (run(1e-3, false) - reference).norm(), euler_fine = (run(5e-4, false) - reference).norm();
  EXPECT_NEAR(euler_coarse / euler_fine, 2, 0.2);
}

}  // namespace
}  // namespace twinsim
