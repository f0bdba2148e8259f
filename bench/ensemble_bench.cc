// An ensemble under the driving noise (`twinsim run SCENE --samples N --jobs J`): 100
// samples of a 10 s drive on the analytic backend (issue 42 asks under 1 s on 2 cores).
//
//   build/ensemble_bench --benchmark_counters_tabular=true
//
// The scene is scenes/drive45.yaml at 60 Hz, driven for 10 s by seeded random commands
// (up to 1.5 m/s and 4 rad/s), its robot drawing its model's driving noise. Timed: the
// rollouts only (RunOmniEnsemble), not the files.
#include <benchmark/benchmark.h>

#include "scene/scene.h"
#include "scene/scene_ensemble.h"

namespace twinsim {
namespace {

void BM_Ensemble(benchmark::State& state) {
  Scene scene = LoadScene(std::string(TWINSIM_SOURCE_DIR) + "/scenes/drive45.yaml");
  scene.frame_rate = 60;
  scene.duration = 10;
  for (SceneRobot& r : scene.robots) {
    r.model.driving_noise.simulated = true;
    r.commands = CommandSpec{};
    r.commands.type = "random";
    r.commands.max_speed = 1.5;
    r.commands.max_omega = 4.0;
  }
  OmniEnsembleOptions options;
  options.samples = static_cast<int>(state.range(0));
  options.jobs = static_cast<int>(state.range(1));
  for (auto _ : state) {
    const OmniEnsemble e = RunOmniEnsemble(scene, "analytic", "", options);
    benchmark::DoNotOptimize(e.paths.back().back().x);
  }
  state.counters["samples"] = static_cast<double>(options.samples);
  state.counters["jobs"] = static_cast<double>(options.jobs);
}
BENCHMARK(BM_Ensemble)->Args({100, 1})->Args({100, 2})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
