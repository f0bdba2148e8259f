// The omni observer's cost (issue 40): replaying a minute at 60 Hz through the model's
// Kalman filter against the open-loop tracker, on the analytic engine and on ODE; the
// same minute predicted far ahead with the covariance, as the driving noise's search
// replays it; and identify of that minute (the goal: a 60 s log within 60 s on two cores). The log is the
// wandering plant of the tests (tests/estimation/wandering_plant.h: a robot with driving
// noise, written apart from the models).
//
//   build/observer_bench
#include <benchmark/benchmark.h>

#include "../tests/estimation/wandering_plant.h"
#include "analysis/omni_replay.h"
#include "identification_omni/omni_identification.h"
#include "robots/omni/omni_model.h"

namespace twinsim {
namespace {

const testing::PlantRecording& Minute() {
  static const testing::PlantRecording rec = testing::RecordWanderingPlant(testing::WanderingPlant{}, 60, 5);
  return rec;
}

OmniModel Model() { return LoadOmniModel(std::string(TWINSIM_SOURCE_DIR) + "/models/omni4.yaml"); }

// Arg 0: 0 analytic, 1 ode; arg 1: 0 tracker, 1 observer.
void BM_ReplayMinute(benchmark::State& state) {
  const OmniModel model = Model();
  OmniReplayOptions o;
  o.backend = state.range(0) == 0 ? "analytic" : "ode";
  o.state = state.range(1) == 0 ? OmniReplayState::kTracker : OmniReplayState::kObserver;
  double rmse = 0;
  for (auto _ : state) rmse = PositionRmse(Minute().log, ReplayOmniLog(model, Minute().log, o));
  state.counters["rmse_mm"] = 1000 * rmse;
  state.counters["frames"] = static_cast<double>(Minute().log.rows.size());
  state.SetLabel(o.backend + ", " + OmniReplayStateName(o.state));
}
BENCHMARK(BM_ReplayMinute)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

// The driving noise's search replays so: the observer's predictions 63 frames ahead
// (16 and 4 on the way) from every 4th frame, each with its covariance (the Kalman
// filter's propagation at every frame ahead), on the analytic engine.
void BM_ReplayMinuteWithCovariance(benchmark::State& state) {
  OmniModel model = Model();
  model.driving_noise.sd = {0.02, 0.02, 0.1};
  model.driving_noise.drift.sd = {state.range(0) ? 0.01 : 0.0, 0, 0};
  OmniReplayOptions o;
  o.state = OmniReplayState::kObserver;
  o.horizon = 63;
  o.also = {4, 16};
  o.stride = 4;
  o.covariance = true;
  double trace = 0;
  for (auto _ : state) {
    const OmniReplayResult r = ReplayOmniLog(model, Minute().log, o);
    trace = 0;
    for (const Eigen::Matrix3d& c : r.covariance) trace += c.trace();
  }
  state.counters["trace_sum"] = trace;
  state.SetLabel(state.range(0) ? "12 states (a drift)" : "9 states");
}
BENCHMARK(BM_ReplayMinuteWithCovariance)->DenseRange(0, 1)->Unit(benchmark::kMillisecond);

void BM_IdentifyMinute(benchmark::State& state) {
  const OmniModel model = Model();
  OmniIdentificationOptions options;
  options.state = state.range(0) == 0 ? OmniReplayState::kTracker : OmniReplayState::kObserver;
  OmniIdentificationReport report;
  for (auto _ : state) report = IdentifyOmni(model, {Minute().log}, {}, options, nullptr);
  state.counters["evaluations"] = report.evaluations;
  state.counters["held_out_mm"] = 1000 * report.Gap(report.held_out, "identified model")->rmse;
  state.SetLabel(OmniReplayStateName(options.state));
}
BENCHMARK(BM_IdentifyMinute)->DenseRange(0, 1)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
