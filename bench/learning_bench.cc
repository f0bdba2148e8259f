// Speed of the learned simulator (issue 3 goals):
//   training on 10 minutes of 30 fps data: linear <= 1 s, neural <= 60 s;
//   one prediction <= 5 us; the learned backend >= 10,000 times real time (one robot).
//
//   build/learning_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <memory>

#include "backends/omni_backend_factory.h"
#include "learning/omni_predictor.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"

namespace twinsim {
namespace {

OmniModel Model() { return LoadOmniModel(std::string(TWINSIM_SOURCE_DIR) + "/models/omni4.yaml"); }

// Ten minutes of random excitation at 30 fps (the analytic backend: the data's speed
// does not matter here, only its size).
const OmniLog& TenMinutes() {
  static const OmniLog log = [] {
    const OmniModel m = Model();
    CommandSpec random;
    random.type = "random";
    random.max_centripetal = 2.0;
    random.leash = 2.0;
    std::vector<SimRobot> robots;
    robots.push_back(SimRobot{"r", m, Pose2{}, MakeCommandSource(random, 11, 0, 600, Pose2{})});
    Simulation sim(std::move(robots), MakeOmniBackend("analytic", {m}, FieldModel{}, FrameTiming{}), 11);
    const SimulationResult r = sim.Run(18001);
    std::vector<OmniLogRow> rows;
    for (const auto& f : r.frames[0]) rows.push_back({f.t, f.seen, f.command});
    return ParseOmniLog(FormatOmniLog(rows), "ten_minutes.csv");
  }();
  return log;
}

std::shared_ptr<OmniPredictor> Trained(const std::string& kind) {
  OmniTrainOptions options;
  options.kind = kind;
  return std::make_shared<OmniPredictor>(TrainOmniPredictor(Model(), {TenMinutes()}, options));
}

void BM_Train(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  state.SetLabel(kind + ", 10 min at 30 fps");
  TenMinutes();
  for (auto _ : state) {
    OmniTrainOptions options;
    options.kind = kind;
    benchmark::DoNotOptimize(TrainOmniPredictor(Model(), {TenMinutes()}, options));
  }
}
BENCHMARK(BM_Train)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_Predict(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  state.SetLabel(kind);
  const auto p = Trained(kind);
  std::vector<double> x(42);
  for (int k = 0; k < 42; ++k) x[static_cast<std::size_t>(k)] = 0.01 * k;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p->PredictDelta(x.data()));
    x[0] += 1e-9;
  }
}
BENCHMARK(BM_Predict)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_LearnedBackend(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  state.SetLabel(kind + ", 1 robot, full loop");
  const OmniModel m = Model();
  OmniBackendOptions options;
  options.predictor = Trained(kind);
  CommandSpec random;
  random.type = "random";
  const double seconds = 60;
  for (auto _ : state) {
    std::vector<SimRobot> robots;
    robots.push_back(SimRobot{"r", m, Pose2{}, MakeCommandSource(random, 1, 0, seconds, Pose2{})});
    Simulation sim(std::move(robots), MakeOmniBackend("learned", {m}, FieldModel{}, FrameTiming{}, options), 1);
    benchmark::DoNotOptimize(sim.Run(static_cast<int>(seconds * 30)));
  }
  state.counters["x_real_time"] = benchmark::Counter(seconds, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LearnedBackend)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
