// Simulated seconds per wall second, twinsim's full loop against the raw engine.
//
//   build/sim_bench --benchmark_counters_tabular=true
//
// BM_Loop: the whole pipeline a `twinsim run` does: delay lines, camera noise, the
// on-board controller, motors, encoders, the engine, and formatting the CSV log.
// BM_RawEngine: the same engine stepping the same bodies with precomputed wheel
// torques and nothing else (a constant wrench whose sign flips every half second, so
// the robots shuttle at about 1 m/s on all their wheels like the loop's robots do). Both step physics at 300 Hz (60 fps, 5 sub-steps: grSim's rate); the
// counter `x_real_time` is simulated seconds per wall second.
#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include "backends/omni_backend_factory.h"
#include "robots/omni/omni_kinematics.h"
#include "robots/omni/omni_log.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"

namespace twinsim {
namespace {

constexpr double kFrameRate = 60;   // Hz
constexpr int kSubsteps = 5;        // 300 Hz physics
constexpr double kSeconds = 10;     // simulated per iteration

OmniModel BenchModel() { return LoadOmniModel(std::string(TWINSIM_SOURCE_DIR) + "/models/omni4.yaml"); }

Pose2 StartOf(int i) { return Pose2{-4.5 + 0.4 * (i % 22), -2.0 + 2.0 * (i / 22), 0}; }

const char* kEngines[] = {"ode", "bullet", "analytic"};

void BM_Loop(benchmark::State& state) {
  const std::string engine = kEngines[state.range(0)];
  state.SetLabel(engine);
  const int n = static_cast<int>(state.range(1));
  const OmniModel model = BenchModel();
  CommandSpec random;
  random.type = "random";
  random.max_speed = 1.0;  // keeps 22 robots off each other and the walls for 10 s
  FrameTiming timing{kFrameRate, kSubsteps};
  const int frames = static_cast<int>(kSeconds * kFrameRate);
  for (auto _ : state) {
    std::vector<SimRobot> robots;
    std::vector<OmniModel> models(static_cast<std::size_t>(n), model);
    for (int i = 0; i < n; ++i)
      robots.push_back(SimRobot{"r" + std::to_string(i), model, StartOf(i),
                                MakeCommandSource(random, 1, i, kSeconds, StartOf(i))});
    std::unique_ptr<OmniBackend> backend;
    try {
      backend = MakeOmniBackend(engine, models, FieldModel{}, timing);
    } catch (const std::exception& e) {
      state.SkipWithError(e.what());
      return;
    }
    Simulation sim(std::move(robots), std::move(backend), 1);
    SimulationResult result = sim.Run(frames);
    for (const auto& robot : result.frames) {
      std::vector<OmniLogRow> rows;
      rows.reserve(robot.size());
      for (const auto& f : robot)
        if (f.observed) rows.push_back({f.t, f.seen, f.command});
      benchmark::DoNotOptimize(FormatOmniLog(rows));
    }
  }
  state.counters["x_real_time"] = benchmark::Counter(kSeconds, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_RawEngine(benchmark::State& state) {
  const std::string engine_name = kEngines[state.range(0)];
  state.SetLabel(engine_name);
  const int n = static_cast<int>(state.range(1));
  const OmniModel model = BenchModel();
  OmniKinematics kin(model);
  const Eigen::VectorXd torques = kin.WheelTorques(Eigen::Vector3d(4.0, 2.0, 0.05));
  const int flip_every = static_cast<int>(kFrameRate * kSubsteps / 2);
  const int steps = static_cast<int>(kSeconds * kFrameRate) * kSubsteps;
  const double dt = 1.0 / (kFrameRate * kSubsteps);
  for (auto _ : state) {
    std::unique_ptr<OmniEngine> engine;
    try {
      engine = MakeOmniEngine(engine_name, std::vector<OmniModel>(static_cast<std::size_t>(n), model), FieldModel{});
    } catch (const std::exception& e) {
      state.SkipWithError(e.what());
      return;
    }
    for (int i = 0; i < n; ++i) {
      OmniBodyState s;
      s.pose = StartOf(i);
      s.wheel_speeds = Eigen::VectorXd::Zero(model.num_wheels());
      engine->SetState(i, s);
    }
    for (int k = 0; k < steps; ++k) {
      if (k % flip_every == 0) {
        const double sign = (k / flip_every) % 2 == 0 ? 1.0 : -1.0;
        // Start with half a swing so that the robots shuttle about their start.
        const double scale = k == 0 ? 0.5 : 1.0;
        for (int i = 0; i < n; ++i) engine->SetWheelTorques(i, sign * scale * torques);
      }
      engine->Step(dt);
    }
    benchmark::DoNotOptimize(engine->GetState(0));
  }
  state.counters["x_real_time"] = benchmark::Counter(kSeconds, benchmark::Counter::kIsIterationInvariantRate);
  // Microseconds per engine step (shown with Google Benchmark's "s" suffix).
  state.counters["us_per_step"] = benchmark::Counter(steps * 1e-6, benchmark::Counter::kIsIterationInvariantRate |
                                                                          benchmark::Counter::kInvert);
}

void Args(benchmark::internal::Benchmark* b) {
  for (int e = 0; e < 3; ++e)
    for (int n : {1, 11, 22}) b->Args({e, n});
  b->ArgNames({"engine", "robots"})->Unit(benchmark::kMillisecond)->MinTime(1.0);
}

BENCHMARK(BM_RawEngine)->Apply(Args);
BENCHMARK(BM_Loop)->Apply(Args);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
