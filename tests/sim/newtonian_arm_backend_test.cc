// The Newtonian arm backend's step: the friction solve's M serving the analytic engine's
// first RK4 stage (the same trajectory as the engine's own ABA, to round-off), and the
// two integrators of a joint_flexibility (explicit, trapezoidal) against a fine-step RK4
// of the coupled link and motor equations (FlexibleRk4Step): accuracy with stated
// tolerances, energy, stability at stiff springs, the resonance.
#include "sim/newtonian_arm_backend.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <iostream>
#include <memory>

#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_integrators.h"
#include "sim/arm_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

using ::twinsim::testing::SourcePath;

// The analytic engine without its StepFromAcceleration: every RK4 stage by its own ABA.
class OwnStagesEngine final : public ArmEngine {
 public:
  explicit OwnStagesEngine(const ArmModel& model) : engine_(MakeArmEngine("analytic", model)) {}
  std::string name() const override { return engine_->name(); }
  int dof() const override { return engine_->dof(); }
  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) override { engine_->Reset(q, qd); }
  void Step(const Eigen::VectorXd& tau, double dt) override { engine_->Step(tau, dt); }
  const Eigen::VectorXd& q() const override { return engine_->q(); }
  const Eigen::VectorXd& qd() const override { return engine_->qd(); }
  ArmEngineState Save() const override { return engine_->Save(); }
  void Restore(const ArmEngineState& state) override { engine_->Restore(state); }

 private:
  std::unique_ptr<ArmEngine> engine_;
};

ArmModel Rrr() { return LoadArmModel(SourcePath("models/rrr.yaml")); }

// The RRR arm without friction or gravity, its elbow on a spring k (N·m/rad) with
// damping 0.2 N·m·s/rad and a 0.01 kg m^2 motor, stepped by `integrator`.
ArmModel FlexibleRrr(double k, FlexibilityIntegrator integrator, bool gravity = false) {
  ArmModel m = Rrr();
  for (ArmJoint& j : m.joints) j.viscous = j.coulomb = 0;
  if (!gravity) m.gravity.setZero();
  AddArmEffect(ArmEffect{"joint_flexibility", 2, {{"k", k}, {"damping", 0.2}, {"motor_inertia", 0.01}}}, m.dof(),
               &m.effects);
  m.flexibility_integrator = integrator;
  return m;
}

// Open-loop drive (N·m) at t (s): every joint swings, and the elbow gets a step at 0.1 s
// that rings its spring.
Eigen::VectorXd Drive(double t) {
  return Eigen::Vector3d(0.3 + 0.5 * std::sin(2 * kPi * 3 * t), 0.5 * std::sin(2 * kPi * 2 * t),
                         0.2 * std::sin(2 * kPi * 5 * t) + (t >= 0.1 ? 0.5 : 0.0));
}

const Eigen::Vector3d kQ0(0, 0.4, -0.6);

// The links' q at every sample (samples x dof) of the backend driven by Drive.
Eigen::MatrixXd RunBackend(ArmBackend* b, int samples, const Eigen::VectorXd& qd0 = Eigen::Vector3d::Zero()) {
  const double ts = 1e-3;
  b->Reset(kQ0, qd0, Eigen::Vector3d::Zero());
  Eigen::MatrixXd q(samples, b->dof());
  Eigen::VectorXd applied;
  for (int k = 0; k < samples; ++k) {
    q.row(k) = b->q().transpose();
    b->Step(Drive(k * ts), &applied);
  }
  return q;
}

// The same by FlexibleRk4Step at `per_sample` steps per 1 ms sample.
Eigen::MatrixXd RunReference(const ArmModel& m, int samples, int per_sample) {
  const ArmModel plant = ArmPlantModel(m);
  FlexibleArmState x{kQ0, Eigen::Vector3d::Zero(), kQ0, Eigen::Vector3d::Zero()};
  Eigen::MatrixXd q(samples, m.dof());
  for (int k = 0; k < samples; ++k) {
    q.row(k) = x.q.transpose();
    const Eigen::VectorXd u = Drive(k * 1e-3);
    for (int i = 0; i < per_sample; ++i) FlexibleRk4Step(plant, u, 1e-3 / per_sample, &x);
  }
  return q;
}

TEST(NewtonianArmBackend, FrictionSolveServesTheEnginesFirstStageToRoundOff) {
  // The RRR with its friction under the effects of the loop benchmark (a flexible elbow
  // at 3 physics steps per sample): the engine's first stage from the friction solve's
  // M against its own ABA, 2 s.
  for (const bool effects : {false, true}) {
    ArmModel m = Rrr();
    if (effects) {
      AddArmEffect(ArmEffect{"stribeck_friction", 1, {{"c", 0.5}, {"s", 1.0}, {"vs", 0.05}}}, m.dof(), &m.effects);
      AddArmEffect(ArmEffect{"joint_flexibility", 2, {{"k", 600}, {"damping", 0.5}, {"motor_inertia", 0.03}}},
                   m.dof(), &m.effects);
    }
    NewtonianArmBackend shared(m, MakeArmEngine("analytic", m));
    NewtonianArmBackend own(m, std::make_unique<OwnStagesEngine>(m));
    const Eigen::MatrixXd a = RunBackend(&shared, 2000), b = RunBackend(&own, 2000);
    const double gap = (a - b).cwiseAbs().maxCoeff();
    std::cout << "[measured] shared first stage vs own ABA" << (effects ? " (effects)" : "") << ": " << gap
              << " rad over 2 s\n";
    EXPECT_LT(gap, 1e-12);
    EXPECT_GT(a.cwiseAbs().maxCoeff(), 0.5);  // it moved
  }
}

TEST(NewtonianArmBackend, TrapezoidalFlexibilityMatchesTheFineRk4Reference) {
  // 1 s of the open-loop drive. The reference: the coupled equations by RK4 at 10 us.
  // Largest |q - q_ref| over every joint and sample (rad): the measured value and the
  // tolerance asserted, per spring and integrator (docs/benchmarks.md has the table).
  struct Case {
    double k;                      // N·m/rad
    FlexibilityIntegrator integrator;
    int substeps;                  // 0 = automatic
    int expected_substeps;
    double tolerance;              // rad
  };
  const Case cases[] = {
      {5000, FlexibilityIntegrator::kTrapezoidal, 0, 3, 5e-6},    // measured 2.9e-6
      {5000, FlexibilityIntegrator::kTrapezoidal, 1, 1, 3e-5},    // 1.9e-5
      {5000, FlexibilityIntegrator::kExplicit, 0, 9, 2e-4},       // 1.0e-4
      {50000, FlexibilityIntegrator::kTrapezoidal, 0, 8, 3e-6},   // 1.1e-6
      {50000, FlexibilityIntegrator::kTrapezoidal, 1, 1, 1e-5},   // 3.6e-6
      {50000, FlexibilityIntegrator::kExplicit, 0, 28, 1e-4},     // 4.6e-5
  };
  for (const Case& c : cases) {
    const ArmModel m = FlexibleRrr(c.k, c.integrator);
    ArmBackendOptions options;
    options.physics_substeps = c.substeps;
    std::unique_ptr<ArmBackend> b = MakeArmBackend("analytic", m, options);
    EXPECT_EQ(b->physics_substeps(), c.expected_substeps) << c.k;
    const Eigen::MatrixXd q = RunBackend(b.get(), 1000);
    const Eigen::MatrixXd reference = RunReference(m, 1000, 100);
    const double error = (q - reference).cwiseAbs().maxCoeff();
    std::cout << "[measured] k = " << c.k << " "
              << (c.integrator == FlexibilityIntegrator::kTrapezoidal ? "trapezoidal" : "explicit") << ", "
              << b->physics_substeps() << " physics steps per sample: max |q - q_ref| = " << error << " rad\n";
    EXPECT_LT(error, c.tolerance) << c.k;
    EXPECT_GT(reference.cwiseAbs().maxCoeff(), 0.5);  // it moved
  }
}

TEST(NewtonianArmBackend, TrapezoidalFlexibilityIsStableWhereTheExplicitStepDiverges) {
  // k = 5e5 N·m/rad: a 1.2 kHz resonance, h sqrt(k / J_eff) = 7.3 at one 1 ms step.
  ArmBackendOptions one;
  one.physics_substeps = 1;
  const ArmModel explicit_model = FlexibleRrr(5e5, FlexibilityIntegrator::kExplicit);
  ArmSimulation explicit_sim(explicit_model, MakeArmBackend("analytic", explicit_model, one));
  EXPECT_THROW(explicit_sim.Run(1000, [](double t, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Drive(t);
  }),
               CheckFailed);
  const ArmModel m = FlexibleRrr(5e5, FlexibilityIntegrator::kTrapezoidal);
  std::unique_ptr<ArmBackend> b = MakeArmBackend("analytic", m, one);
  const Eigen::MatrixXd q = RunBackend(b.get(), 1000);
  const Eigen::MatrixXd reference = RunReference(m, 1000, 1000);
  const double error = (q - reference).cwiseAbs().maxCoeff();
  std::cout << "[measured] k = 5e5 trapezoidal, 1 physics step per sample: max |q - q_ref| = " << error << " rad\n";
  EXPECT_LT(error, 1e-6);  // measured 3.8e-7
}

// Total energy (J): the links' kinetic and potential energy, the motors' kinetic energy
// and the springs'.
double TotalEnergy(const ArmModel& m, const ArmBackend& b) {
  const ArmBackendState s = b.Save();
  const ArmModel plant = ArmPlantModel(m);
  double e = KineticEnergy(plant, b.q(), b.qd()) + PotentialEnergy(plant, b.q());
  for (int j = 0; j < m.dof(); ++j) {
    const JointEffects fx = m.effects.joint(j);
    if (!fx.flexible()) continue;
    e += 0.5 * fx.motor_inertia * s.motor_qd[j] * s.motor_qd[j] +
         0.5 * fx.stiffness * std::pow(s.motor_q[j] - b.q()[j], 2);
  }
  return e;
}

TEST(NewtonianArmBackend, UndampedFlexibleArmKeepsItsEnergyWithTheTrapezoidalRule) {
  // The RRR under gravity, no friction, an undamped spring k = 5000 on the elbow, no
  // drive, swinging from qd0 for 2 s: largest |E - E0| (E0 = 26 J, the potential
  // energy's zero at the base). The trapezoidal rule keeps it to 1.4e-7 J (measured);
  // the explicit step, whose link takes the spring torque of the step's start, gains
  // energy from an undamped spring at any step (measured: 96 J at 9 steps per sample),
  // so only its number is printed.
  for (const FlexibilityIntegrator integrator : {FlexibilityIntegrator::kTrapezoidal, FlexibilityIntegrator::kExplicit}) {
    ArmModel m = FlexibleRrr(5000, integrator, /*gravity=*/true);
    m.effects.joints[2].flex_damping = 0;
    std::unique_ptr<ArmBackend> b = MakeArmBackend("analytic", m);
    b->Reset(kQ0, Eigen::Vector3d(1, -0.5, 2), Eigen::Vector3d::Zero());
    const double e0 = TotalEnergy(m, *b);
    double drift = 0;
    Eigen::VectorXd applied;
    for (int k = 0; k < 2000; ++k) {
      b->Step(Eigen::Vector3d::Zero(), &applied);
      drift = std::max(drift, std::abs(TotalEnergy(m, *b) - e0));
    }
    const bool trapezoidal = integrator == FlexibilityIntegrator::kTrapezoidal;
    std::cout << "[measured] undamped flexible RRR, " << (trapezoidal ? "trapezoidal" : "explicit") << ", "
              << b->physics_substeps() << " physics steps per sample: max |E - E0| = " << drift << " J of "
              << std::abs(e0) << " J\n";
    if (trapezoidal) {
      EXPECT_LT(drift, 1e-6);
    }
  }
}

TEST(NewtonianArmBackend, FlexibleRk4ReferenceKeepsEnergyAndResonates) {
  // The reference itself: a turntable link (no gravity, J_l about the axis known)
  // behind an undamped spring, from a motor speed step: energy kept to 1e-10 relative
  // and the closed form's resonance sqrt(k (1/J_m + 1/J_l)).
  ArmModel m = Rrr();
  m.joints.resize(1);
  m.gravity.setZero();
  for (ArmJoint& j : m.joints) j.viscous = j.coulomb = 0;
  AddArmEffect(ArmEffect{"joint_flexibility", 0, {{"k", 1000}, {"motor_inertia", 0.02}}}, 1, &m.effects);
  const double link = MassMatrix(m, Eigen::VectorXd::Zero(1))(0, 0);
  FlexibleArmState x{Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1),
                     Eigen::VectorXd::Constant(1, 1.0)};
  auto energy = [&] {
    return 0.5 * link * x.qd[0] * x.qd[0] + 0.5 * 0.02 * x.motor_qd[0] * x.motor_qd[0] +
           0.5 * 1000 * std::pow(x.motor_q[0] - x.q[0], 2);
  };
  const double e0 = energy();
  double drift = 0, crossings = 0, first = 0, last = 0, previous = 0;
  const double h = 1e-5;
  for (int i = 1; i <= 100000; ++i) {
    FlexibleRk4Step(m, Eigen::VectorXd::Zero(1), h, &x);
    drift = std::max(drift, std::abs(energy() - e0));
    const double deflection = x.motor_q[0] - x.q[0];
    if (previous < 0 && deflection >= 0) {
      const double t = h * (i - deflection / (deflection - previous));
      if (crossings == 0) first = t;
      last = t;
      ++crossings;
    }
    previous = deflection;
  }
  const double f = (crossings - 1) / (last - first);
  const double expected = std::sqrt(1000 * (1 / 0.02 + 1 / link)) / (2 * kPi);
  EXPECT_LT(drift, 1e-10 * e0);
  EXPECT_NEAR(f, expected, 1e-6 * expected);
}

}  // namespace
}  // namespace twinsim
