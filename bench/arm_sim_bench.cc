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
// the engine alone, stepping 1 ms at a time with precomputed torques. The counter
// `x_real_time` is simulated seconds per wall second.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

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

void RunLoop(benchmark::State& state, const ArmModel& model) {
  const std::string backend = kBackends[state.range(0)];
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

void BM_ArmLoop(benchmark::State& state) { RunLoop(state, Rrr()); }
BENCHMARK(BM_ArmLoop)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_ArmLoopEffects(benchmark::State& state) { RunLoop(state, WithEffects(Rrr())); }
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

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
