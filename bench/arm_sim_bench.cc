// Simulated seconds per wall second of the arm simulation loop on each backend.
//
//   build/arm_sim_bench --benchmark_counters_tabular=true
//
// The RRR arm (models/rrr.yaml: 1 kHz, one sample of delay, its nominal viscous and
// Coulomb friction) tracks sinusoids under a PD controller with gravity compensation,
// 2 simulated seconds per iteration. BM_ArmLoop: the whole loop (delay line, effects,
// the velocity-level friction solve, the backend at its default internal step).
// BM_ArmLoopEffects: the same with time_delay, saturation, Stribeck friction and a
// 30 Hz joint_flexibility on the elbow (3 physics steps per sample). BM_ArmEngine:
// the engine alone, stepping 1 ms at a time with precomputed torques; BM_ArmBackend:
// the analytic Newtonian backend alone (friction solve and engine) with the loop's
// commands. BM_ArmLoopFlex: the loop on the RRR with a stiff flexible elbow (k = 5000
// N·m/rad, J_m = 0.01 kg m^2: 118 Hz), its joint_flexibility stepped explicitly (/0) or
// by the trapezoidal rule (/1). BM_RrrPart: the dynamics the loop is made of, one call
// each (/0 ABA, /1 M and bias by CRBA, /2 inverse dynamics, /3 the controller). The
// counter `x_real_time` is simulated seconds per wall second.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "backends/arm_backend_factory.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"
#include "sim/arm_simulation.h"

namespace twinsim {
namespace {

constexpr double kSeconds = 2;  // simulated per iteration
const char* kBackends[] = {"analytic", "ode", "bullet"};

ArmModel Rrr() { return LoadArmModel(std::string(TWINSIM_SOURCE_DIR) + "/models/rrr.yaml"); }

ArmModel WithEffects(ArmModel m) {
  AddArmEffect(ArmEffect{"time_delay", 0, {{"delay", 0.002}}}, m.dof(), &m.effects);
  AddArmEffect(ArmEffect{"torque_saturation", 1, {{"limit", 40}}}, m.dof(), &m.effects);
  AddArmEffect(ArmEffect{"stribeck_friction", 1, {{"c", 0.5}, {"s", 1.0}, {"vs", 0.05}}}, m.dof(), &m.effects);
  AddArmEffect(ArmEffect{"joint_flexibility", 2, {{"k", 600}, {"damping", 0.5}, {"motor_inertia", 0.03}}}, m.dof(),
               &m.effects);
  return m;
}

ArmController Tracker(const ArmModel& m) {
  return [&m](double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    const Eigen::Vector3d ref(0.5 * std::sin(3 * t), 0.4 + 0.3 * std::sin(4 * t), -0.6 + 0.4 * std::sin(5 * t));
    const Eigen::Vector3d ref_d(1.5 * std::cos(3 * t), 1.2 * std::cos(4 * t), 2.0 * std::cos(5 * t));
    const Eigen::VectorXd g = InverseDynamics(m, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), false);
    return Eigen::VectorXd(g + Eigen::Vector3d(200, 300, 100).cwiseProduct(ref - q) +
                           Eigen::Vector3d(20, 20, 1).cwiseProduct(ref_d - qd));
  };
}

bool Built(const std::string& backend) {
  const std::vector<std::string> built = AvailableArmEngines();
  return std::find(built.begin(), built.end(), backend) != built.end();
}

void RunLoop(benchmark::State& state, const ArmModel& model, const std::string& backend) {
  state.SetLabel(backend);
  if (!Built(backend)) return state.SkipWithError("backend not compiled");
  const ArmController controller = Tracker(model);
  const int samples = static_cast<int>(kSeconds / model.sample_time);
  ArmSimulation sim(model, MakeArmBackend(backend, model));
  for (auto _ : state) {
    sim.Reset(Eigen::Vector3d(0, 0.4, -0.6), Eigen::Vector3d::Zero());
    benchmark::DoNotOptimize(sim.Run(samples, controller));
  }
  state.counters["x_real_time"] = benchmark::Counter(kSeconds, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["physics_steps"] = sim.physics_substeps();
}

void BM_ArmLoop(benchmark::State& state) { RunLoop(state, Rrr(), kBackends[state.range(0)]); }
BENCHMARK(BM_ArmLoop)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_ArmLoopEffects(benchmark::State& state) {
  RunLoop(state, WithEffects(Rrr()), kBackends[state.range(0)]);
}
BENCHMARK(BM_ArmLoopEffects)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_ArmEngine(benchmark::State& state) {
  const std::string backend = kBackends[state.range(0)];
  state.SetLabel(backend);
  if (!Built(backend)) return state.SkipWithError("backend not compiled");
  const ArmModel model = Rrr();
  const int samples = static_cast<int>(kSeconds / model.sample_time);
  // The torques the loop sent, replayed without the loop.
  ArmSimulation sim(model, MakeArmBackend("analytic", model));
  sim.Reset(Eigen::Vector3d(0, 0.4, -0.6), Eigen::Vector3d::Zero());
  const ArmTrajectory run = sim.Run(samples, Tracker(model));
  auto b = MakeArmEngine(backend, model);
  std::vector<Eigen::VectorXd> torques;
  for (int k = 0; k < samples; ++k) torques.push_back(run.applied.row(k).transpose());
  for (auto _ : state) {
    b->Reset(Eigen::Vector3d(0, 0.4, -0.6), Eigen::Vector3d::Zero());
    for (const Eigen::VectorXd& tau : torques) b->Step(tau, model.sample_time);
    benchmark::DoNotOptimize(b->q());
  }
  state.counters["x_real_time"] = benchmark::Counter(kSeconds, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ArmEngine)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_ArmBackend(benchmark::State& state) {
  const ArmModel model = Rrr();
  const int samples = static_cast<int>(kSeconds / model.sample_time);
  ArmSimulation sim(model, MakeArmBackend("analytic", model));
  sim.Reset(Eigen::Vector3d(0, 0.4, -0.6), Eigen::Vector3d::Zero());
  const ArmTrajectory run = sim.Run(samples, Tracker(model));
  std::vector<Eigen::VectorXd> commands;
  for (int k = 0; k < samples; ++k) commands.push_back(run.command.row(k).transpose());
  std::unique_ptr<ArmBackend> b = MakeArmBackend("analytic", model);
  Eigen::VectorXd applied;
  for (auto _ : state) {
    b->Reset(Eigen::Vector3d(0, 0.4, -0.6), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    for (const Eigen::VectorXd& u : commands) b->Step(u, &applied);
    benchmark::DoNotOptimize(b->q());
  }
  state.counters["x_real_time"] = benchmark::Counter(kSeconds, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ArmBackend)->Unit(benchmark::kMillisecond);

void BM_ArmLoopFlex(benchmark::State& state) {
  ArmModel model = Rrr();
  AddArmEffect(ArmEffect{"joint_flexibility", 2, {{"k", 5000}, {"damping", 0.2}, {"motor_inertia", 0.01}}},
               model.dof(), &model.effects);
  model.flexibility_integrator =
      state.range(0) == 1 ? FlexibilityIntegrator::kTrapezoidal : FlexibilityIntegrator::kExplicit;
  RunLoop(state, model, "analytic");
  state.SetLabel(state.range(0) == 1 ? "analytic, trapezoidal" : "analytic, explicit");
}
BENCHMARK(BM_ArmLoopFlex)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_RrrPart(benchmark::State& state) {
  const ArmModel model = ArmPlantModel(Rrr());
  const Eigen::VectorXd q = Eigen::Vector3d(0.3, 0.5, -0.7), qd = Eigen::Vector3d(0.4, -0.6, 0.9);
  const Eigen::VectorXd tau = Eigen::Vector3d(1, 20, 3);
  const ArmController controller = Tracker(model);
  Eigen::VectorXd out(3), bias(3);
  Eigen::MatrixXd mass(3, 3);
  const char* labels[] = {"ABA", "CRBA + bias", "inverse dynamics", "controller"};
  state.SetLabel(labels[state.range(0)]);
  for (auto _ : state) {
    switch (state.range(0)) {
      case 0: ForwardDynamics(model, q, qd, tau, false, &out); break;
      case 1: MassMatrixAndBias(model, q, qd, &mass, &bias); break;
      case 2: out = InverseDynamics(model, q, qd, tau); break;
      default: out = controller(0.1, q, qd); break;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::DoNotOptimize(mass.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_RrrPart)->DenseRange(0, 3)->Unit(benchmark::kNanosecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
