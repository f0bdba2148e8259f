// Speed of the learned simulator (issue 3 goals):
//   training on 10 minutes of 30 fps data: linear <= 1 s, neural <= 60 s;
//   one prediction <= 5 us; the learned backend >= 10,000 times real time (one robot).
// and of the residual predictor over a Newtonian model (issue 16 goals): one prediction
// <= 5 us, the learned backend with it >= 1,000 times real time (one robot). The second
// argument is the residual's nominal engine: 0 none (the seed's predictor), 1 analytic,
// 2 ode.
//
//   build/learning_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <memory>
#include <optional>

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

std::shared_ptr<OmniPredictor> Trained(const std::string& kind, int residual = 0) {
  OmniTrainOptions options;
  options.kind = kind;
  options.residual = residual > 0;
  options.nominal_engine = residual == 2 ? "ode" : "analytic";
  return std::make_shared<OmniPredictor>(TrainOmniPredictor(Model(), {TenMinutes()}, options));
}

std::string Label(const std::string& kind, int residual) {
  return residual == 0 ? kind : kind + ", residual over " + (residual == 2 ? "ode" : "analytic");
}

void BM_Train(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  const int residual = static_cast<int>(state.range(1));
  state.SetLabel(Label(kind, residual) + ", 10 min at 30 fps");
  TenMinutes();
  for (auto _ : state) benchmark::DoNotOptimize(Trained(kind, residual));
}
BENCHMARK(BM_Train)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({0, 2})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// The learned part alone: the network or ridge fit on encoded inputs.
void BM_Predict(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  state.SetLabel(Label(kind, static_cast<int>(state.range(1))));
  const auto p = Trained(kind, static_cast<int>(state.range(1)));
  const int n = p->info().layout.num_inputs();
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) x[static_cast<std::size_t>(k)] = 0.01 * k;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p->PredictDelta(x.data()));
    x[0] += 1e-9;
  }
}
BENCHMARK(BM_Predict)->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1})->Unit(benchmark::kMicrosecond);

// One whole 1-frame prediction as the learned backend makes it: encoding the window and,
// for a residual predictor, its nominal model's frame (physics steps, controller) and
// the correction.
void BM_PredictFrame(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  const int residual = static_cast<int>(state.range(1));
  state.SetLabel(Label(kind, residual));
  const auto p = Trained(kind, residual);
  const OmniModel m = Model();
  std::optional<NominalOmniTrack> track;
  if (residual) {
    track.emplace(p->MakeNominalTrack(m));
    track->Reset(Pose2{}, Twist2{1.0, 0.2, 0.5});
  }
  std::vector<Pose2> poses(6);
  for (int j = 0; j < 6; ++j) poses[static_cast<std::size_t>(j)] = Pose2{0.033 * j, 0.007 * j, 0.017 * j};
  const std::vector<Twist2> commands(6, Twist2{1.0, 0.2, 0.5});
  for (auto _ : state) {
    if (track) {
      benchmark::DoNotOptimize(p->Step(poses.data(), commands.data(), &*track));
      track->Correct(poses.back());  // keep it where the window is
    } else {
      benchmark::DoNotOptimize(p->Predict(poses.data(), commands.data()));
    }
  }
}
BENCHMARK(BM_PredictFrame)->Args({0, 0})->Args({0, 1})->Args({1, 1})->Args({0, 2})->Unit(benchmark::kMicrosecond);

void BM_LearnedBackend(benchmark::State& state) {
  const std::string kind = state.range(0) == 0 ? "linear" : "mlp";
  const int residual = static_cast<int>(state.range(1));
  state.SetLabel(Label(kind, residual) + ", 1 robot, full loop");
  const OmniModel m = Model();
  OmniBackendOptions options;
  options.predictor = Trained(kind, residual);
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
BENCHMARK(BM_LearnedBackend)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({0, 2})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
