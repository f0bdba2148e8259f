// One conformance suite over every arm backend built into this binary: free swinging,
// energy, a computed-torque trajectory, the delay convention and save/restore, all
// through the arm simulation loop (sim/arm_simulation.h). The tolerances are a few
// times the agreement measured (docs/arm_backends.md gives the numbers).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <iostream>

#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_model.h"
#include "sim/arm_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

using ::twinsim::testing::SourcePath;

ArmModel Rrr() { return LoadArmModel(SourcePath("models/rrr.yaml")); }

ArmModel Frictionless(ArmModel m) {
  for (ArmJoint& j : m.joints) j.viscous = j.coulomb = 0;
  return m;
}

// A pose away from every symmetry, the waist turning: all three joints couple.
Eigen::VectorXd StartQ() { return Eigen::Vector3d(0.3, 0.5, -0.8); }
Eigen::VectorXd StartQd() { return Eigen::Vector3d(0.5, 0.0, 0.0); }

ArmTrajectory FreeSwing(const std::string& backend, const ArmModel& m, double seconds,
                        const ArmBackendOptions& options = {}) {
  ArmSimulation sim(m, MakeArmBackend(backend, m, options));
  sim.Reset(StartQ(), StartQd());
  return sim.Run(static_cast<int>(std::lround(seconds / m.sample_time)) + 1, {});
}

double MaxAbsDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff(); }

class ArmBackendConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(ArmBackendConformance, ReadsBackTheStateItWasResetTo) {
  const ArmModel m = Rrr();
  auto b = MakeArmEngine(GetParam(), m);
  EXPECT_EQ(b->name(), GetParam());
  EXPECT_EQ(b->dof(), 3);
  const Eigen::Vector3d q(2.5, -1.0, 3.0), qd(0.3, -0.2, 0.1);
  b->Reset(q, qd);
  EXPECT_LT((b->q() - q).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((b->qd() - qd).cwiseAbs().maxCoeff(), 1e-12);
  // One tiny step: q moves by qd dt (revolute angles beyond pi stay unwrapped).
  b->Step(Eigen::Vector3d::Zero(), 1e-6);
  EXPECT_LT((b->q() - (q + 1e-6 * qd)).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_THROW(b->Reset(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()), std::invalid_argument);
  EXPECT_THROW(b->Step(Eigen::Vector3d::Zero(), 0), std::invalid_argument);
}

TEST_P(ArmBackendConformance, FreeSwingAgreesWithTheReferenceOverTwoSeconds) {
  // The reference: the analytic model with RK4 at 0.1 ms (within 1e-10 rad of 10 us).
  // The arm falls from 0.5 rad above horizontal through the hanging pose and back.
  const ArmModel m = Frictionless(Rrr());
  ArmBackendOptions fine;
  fine.max_step = 1e-4;
  const ArmTrajectory ref = FreeSwing("analytic", m, 2.0, fine);
  const ArmTrajectory run = FreeSwing(GetParam(), m, 2.0);
  const double q_error = MaxAbsDiff(run.q, ref.q);
  const double qd_error = MaxAbsDiff(run.qd, ref.qd);
  std::cout << "[measured] " << GetParam() << " free swing 2 s: max |q - q_ref| = " << q_error
            << " rad, max |qd - qd_ref| = " << qd_error << " rad/s\n";
  // Measured (docs/arm_backends.md): analytic and bullet (both RK4 at 1 ms) 2.3e-7 rad
  // and 2.2e-6 rad/s; ode (first order, 0.125 ms steps) 1.1e-2 rad and 0.089 rad/s.
  const bool rk4 = GetParam() != "ode";
  EXPECT_LT(q_error, rk4 ? 1e-6 : 2e-2);
  EXPECT_LT(qd_error, rk4 ? 1e-5 : 0.2);
  // It really swung: the shoulder went through more than 1.5 rad.
  EXPECT_GT(ref.q.col(1).maxCoeff() - ref.q.col(1).minCoeff(), 1.5);
  if (GetParam() == "bullet") {
    // Featherstone's algorithm in Bullet and Newton-Euler with the mass matrix here,
    // both under RK4 at 1 ms: two implementations of the same dynamics.
    const ArmTrajectory analytic = FreeSwing("analytic", m, 2.0);
    std::cout << "[measured] bullet vs analytic free swing 2 s: max |dq| = " << MaxAbsDiff(run.q, analytic.q)
              << " rad\n";
    EXPECT_LT(MaxAbsDiff(run.q, analytic.q), 1e-9);
  }
}

// A chain that no DH table would give: tilted joint origins, skew axes, inertia tensors
// with products of inertia, and a prismatic second joint.
ArmModel SkewChain() {
  Rng rng(7);
  ArmModel m;
  m.name = "skew";
  for (int i = 0; i < 4; ++i) {
    ArmJoint j;
    j.name = "j" + std::to_string(i + 1);
    j.type = i == 1 ? JointType::kPrismatic : JointType::kRevolute;
    j.origin = Eigen::Isometry3d::Identity();
    j.origin.translate(Eigen::Vector3d(rng.Uniform(-0.2, 0.2), rng.Uniform(-0.2, 0.2), rng.Uniform(0.05, 0.3)));
    j.origin.rotate(Eigen::AngleAxisd(rng.Uniform(-2, 2), Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-1, 1), 1).normalized()));
    j.axis = Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
    j.child.mass = rng.Uniform(0.5, 3);
    j.child.com = Eigen::Vector3d(rng.Uniform(-0.15, 0.15), rng.Uniform(-0.15, 0.15), rng.Uniform(-0.15, 0.15));
    const Eigen::Vector3d s(rng.Uniform(0.05, 0.3), rng.Uniform(0.05, 0.3), rng.Uniform(0.05, 0.3));  // m, a box
    const Eigen::Vector3d d = j.child.mass / 12.0 * Eigen::Vector3d(s.y() * s.y() + s.z() * s.z(),
                                                                   s.x() * s.x() + s.z() * s.z(),
                                                                   s.x() * s.x() + s.y() * s.y());
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(rng.Uniform(-3, 3), Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    j.child.inertia = rot * d.asDiagonal() * rot.transpose();
    m.joints.push_back(j);
  }
  return m;
}

TEST_P(ArmBackendConformance, AgreesOnASkewChainWithAPrismaticJoint) {
  const ArmModel m = SkewChain();
  ASSERT_EQ(m.Validate(), "");
  const Eigen::Vector4d q0(0.4, 0.05, -0.7, 1.2), qd0(0.8, -0.3, 1.5, -2.0);
  auto swing = [&](const std::string& backend, double max_step) {
    ArmBackendOptions options;
    options.max_step = max_step;
    ArmSimulation sim(m, MakeArmBackend(backend, m, options));
    sim.Reset(q0, qd0);
    return sim.Run(1001, {});
  };
  const ArmTrajectory ref = swing("analytic", 1e-4);
  const ArmTrajectory run = swing(GetParam(), 0);
  const double error = MaxAbsDiff(run.q, ref.q);
  std::cout << "[measured] " << GetParam() << " skew chain 1 s: max |q - q_ref| = " << error << " (rad or m)\n";
  // Measured: analytic and bullet 5.8e-10, ode 1.5e-3.
  EXPECT_LT(error, GetParam() == "ode" ? 3e-3 : 1e-8);
  EXPECT_GT(ref.q.col(1).maxCoeff() - ref.q.col(1).minCoeff(), 0.05) << "the slider hardly moved";
}

TEST_P(ArmBackendConformance, FreeSwingConservesEnergy) {
  const ArmModel m = Frictionless(Rrr());
  const ArmTrajectory run = FreeSwing(GetParam(), m, 2.0);
  const double e0 = KineticEnergy(m, StartQ(), StartQd()) + PotentialEnergy(m, StartQ());
  double drift = 0, swing = 0;
  for (int k = 0; k < run.t.size(); ++k) {
    const Eigen::VectorXd q = run.q.row(k).transpose(), qd = run.qd.row(k).transpose();
    const double kinetic = KineticEnergy(m, q, qd);
    drift = std::max(drift, std::abs(kinetic + PotentialEnergy(m, q) - e0));
    swing = std::max(swing, kinetic);
  }
  std::cout << "[measured] " << GetParam() << " free swing 2 s: max |E - E0| = " << drift
            << " J (kinetic energy up to " << swing << " J)\n";
  // Measured: analytic and bullet 1.7e-7 J, ode 0.030 J, of a swing of 20 J.
  EXPECT_LT(drift, GetParam() == "ode" ? 0.06 : 1e-6);
}

TEST_P(ArmBackendConformance, FollowsAComputedTorqueTrajectory) {
  // Feedforward only: tau = ID(q_ref, qd_ref, qdd_ref) with the model's friction at the
  // middle of the sample it will act over (D samples after it is sent). Sinusoids of
  // +-0.5..0.6 rad at 0.8..1.1 Hz about a pose below the horizontal, where gravity does
  // not amplify errors open loop.
  const Eigen::Vector3d q0(0.2, -1.2, 0.5), amp(0.6, 0.5, 0.6), w(5.0, 6.0, 7.0);  // rad, rad, rad/s
  auto ref = [&](double t, Eigen::VectorXd* q, Eigen::VectorXd* qd, Eigen::VectorXd* qdd) {
    *q = q0 + amp.cwiseProduct(Eigen::Vector3d((w * t).array().sin()));
    *qd = amp.cwiseProduct(w).cwiseProduct(Eigen::Vector3d((w * t).array().cos()));
    *qdd = -amp.cwiseProduct(w).cwiseProduct(w).cwiseProduct(Eigen::Vector3d((w * t).array().sin()));
  };
  auto follow = [&](const ArmModel& m) {
    const double ts = m.sample_time;
    auto torque = [&](double t) {
      Eigen::VectorXd q, qd, qdd;
      ref(t, &q, &qd, &qdd);
      return InverseDynamics(m, q, qd, qdd, /*friction=*/true);
    };
    ArmSimulation sim(m, MakeArmBackend(GetParam(), m));
    Eigen::VectorXd q, qd, qdd;
    ref(0, &q, &qd, &qdd);
    EXPECT_EQ(m.delay_samples, 1);
    sim.Reset(q, qd, torque(0.5 * ts));  // the command in flight acts over the first sample
    const ArmTrajectory run = sim.Run(2001, [&](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
      return torque(t + (m.delay_samples + 0.5) * ts);
    });
    double error = 0;
    for (int k = 0; k < run.t.size(); ++k) {
      ref(run.t[k], &q, &qd, &qdd);
      error = std::max(error, (run.q.row(k).transpose() - q).cwiseAbs().maxCoeff());
    }
    return error;
  };
  const double with_friction = follow(Rrr());
  ArmModel viscous_only = Rrr();
  for (ArmJoint& j : viscous_only.joints) j.coulomb = 0;
  const double viscous = follow(viscous_only);
  std::cout << "[measured] " << GetParam() << " computed-torque feedforward 2 s: max |q - q_ref| = " << with_friction
            << " rad (" << viscous << " rad without Coulomb friction)\n";
  // Measured: with the RRR arm's friction 1.6e-3 rad on every backend (each Coulomb
  // reversal happens within a sample, not at the instant the feedforward assumes);
  // without Coulomb friction analytic and bullet 1.4e-5 rad, ode 3.8e-4 rad.
  EXPECT_LT(with_friction, 3e-3);
  EXPECT_LT(viscous, GetParam() == "ode" ? 1e-3 : 5e-5);
}

TEST_P(ArmBackendConformance, ACommandActsAfterTheModelsDelay) {
  // A torque step sent at sample k moves nothing before sample k + D + 1.
  for (int delay : {0, 1, 3}) {
    ArmModel m = Frictionless(Rrr());
    m.delay_samples = delay;
    const int k = 50;
    auto run = [&](bool step) {
      ArmSimulation sim(m, MakeArmBackend(GetParam(), m));
      sim.Reset(StartQ(), Eigen::Vector3d::Zero());
      return sim.Run(k + delay + 3, [&](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
        return Eigen::VectorXd(Eigen::Vector3d(0, 0, step && t >= k * m.sample_time - 1e-12 ? 5.0 : 0.0));
      });
    };
    const ArmTrajectory quiet = run(false), stepped = run(true);
    const int first = k + delay + 1;
    for (int i = 0; i < first; ++i) {
      EXPECT_EQ(stepped.q.row(i), quiet.q.row(i)) << "delay " << delay << ", sample " << i;
      EXPECT_EQ(stepped.qd.row(i), quiet.qd.row(i)) << "delay " << delay << ", sample " << i;
    }
    // At k + D + 1 the elbow's velocity has taken 5 N·m over one sample: dqd = Ts M^-1 tau.
    const Eigen::VectorXd q = quiet.q.row(first - 1).transpose();
    const Eigen::MatrixXd minv = MassMatrix(m, q).inverse();
    const Eigen::VectorXd expected = m.sample_time * minv * Eigen::Vector3d(0, 0, 5.0);
    const Eigen::VectorXd got = (stepped.qd.row(first) - quiet.qd.row(first)).transpose();
    EXPECT_NEAR(got[2], expected[2], 0.02 * std::abs(expected[2])) << "delay " << delay;
    EXPECT_EQ(stepped.command(k, 2), 5.0);
    EXPECT_EQ(stepped.applied(k + delay, 2), 5.0);
    EXPECT_EQ(stepped.applied(k + delay - 1, 2), 0.0);
  }
}

TEST_P(ArmBackendConformance, RestoringAStateRepeatsTheRunBitForBit) {
  const ArmModel m = Rrr();  // with friction: the stick-slip solve is part of the state's future
  ArmSimulation sim(m, MakeArmBackend(GetParam(), m));
  sim.Reset(StartQ(), StartQd());
  auto controller = [](double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    return Eigen::VectorXd(-5.0 * qd + Eigen::Vector3d(std::sin(7 * t), 2 * std::cos(3 * t), 0.5));
  };
  sim.Run(300, controller);
  const ArmSimulationState saved = sim.Save();
  const ArmTrajectory first = sim.Run(300, controller);
  sim.Restore(saved);
  const ArmTrajectory second = sim.Run(300, controller);
  EXPECT_EQ(first.q, second.q);
  EXPECT_EQ(first.qd, second.qd);
  EXPECT_EQ(first.t, second.t);
  // A state restored into a second backend of the same kind continues identically.
  ArmSimulation other(m, MakeArmBackend(GetParam(), m));
  other.Restore(saved);
  const ArmTrajectory third = other.Run(300, controller);
  EXPECT_EQ(first.q, third.q);
  EXPECT_EQ(first.qd, third.qd);
}

TEST_P(ArmBackendConformance, ReportsADivergenceWithJointTimeAndValue) {
  const ArmModel m = Frictionless(Rrr());
  ArmSimulation sim(m, MakeArmBackend(GetParam(), m));
  try {
    sim.Run(1000, [](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
      return Eigen::VectorXd(Eigen::Vector3d(t > 0.0095 ? 1e6 : 0.0, 0, 0));
    });
    FAIL() << "expected a divergence";
  } catch (const CheckFailed& e) {
    const std::string what = e.what();
    // Sent at sample 10, acting over sample 11 (one sample of delay), seen at 12.
    EXPECT_NE(what.find("diverged at t = 0.012 s (sample 12)"), std::string::npos) << what;
    EXPECT_NE(what.find("joint 1 'waist' qd = "), std::string::npos) << what;
    EXPECT_NE(what.find(" rad/s"), std::string::npos) << what;
    EXPECT_NE(what.find("on backend " + GetParam()), std::string::npos) << what;
    // The sample before, every joint's position and velocity.
    EXPECT_NE(what.find("last good state at t = 0.011 s: q1 = "), std::string::npos) << what;
    EXPECT_NE(what.find(", qd3 = "), std::string::npos) << what;
  }
  ArmSimulation nan(m, MakeArmBackend(GetParam(), m));
  try {
    nan.Step([](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
      return Eigen::VectorXd(Eigen::Vector3d(0, NAN, 0));
    });
    FAIL() << "expected a refused command";
  } catch (const CheckFailed& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite torque to joint 2 'shoulder' at t = 0 s"), std::string::npos)
        << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Built, ArmBackendConformance, ::testing::ValuesIn(AvailableArmEngines()),
                         [](const auto& info) { return info.param; });

TEST(ArmBackendFactory, RefusesUnknownNamesAndBadOptions) {
  const ArmModel m = Rrr();
  try {
    MakeArmBackend("mujoco", m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown arm backend 'mujoco' (known: analytic, ode, bullet, learned)");
  }
  ArmBackendOptions bad;
  bad.max_step = -1;
  EXPECT_THROW(MakeArmBackend("analytic", m, bad), InputError);
  // A model that does not Validate() is bad input wherever it is caught, for every backend.
  ArmModel heavy = m;
  heavy.joints[1].child.mass = -1;
  for (const std::string& name : AvailableArmEngines()) {
    try {
      MakeArmBackend(name, heavy);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("mass must be positive"), std::string::npos) << name << ": " << e.what();
    }
  }
  const std::vector<std::string> built = AvailableArmEngines();
  if (std::find(built.begin(), built.end(), "bullet") == built.end()) {
    try {
      MakeArmBackend("bullet", m);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_STREQ(e.what(), "bullet backend not compiled; rebuild with -DTWINSIM_WITH_BULLET=ON");
    }
  }
  // The factory knows the learned backend too; it needs a predictor.
  const std::vector<std::string> names = AvailableArmBackends();
  EXPECT_EQ(names.back(), "learned");
  EXPECT_THROW(MakeArmBackend("learned", m), InputError);
}

}  // namespace
}  // namespace twinsim
