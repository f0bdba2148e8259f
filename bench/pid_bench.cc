// Speed of PID learning (issue 6 goal): 10 iterations of 20 test runs in at most 10 s
// on this 2-core machine (seed 000's robot needed a few minutes of real driving).
//
//   build/pid_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "tuning/pid_tuning.h"

namespace twinsim {
namespace {

// One whole learning run from zeros: 10 iterations x (20 perturbed + 1 current) test
// runs of 3.2 s each, on the named backend, with `threads` workers.
void BM_TenIterationsOfTwentyRuns(benchmark::State& state, const std::string& backend) {
  const Scene scene = LoadScene(std::string(TWINSIM_SOURCE_DIR) + "/scenes/tune_pid_zeros.yaml");
  PidTuningOptions o = ReadPidTuningOptions(scene);
  o.iterations = 10;
  o.sets_per_iteration = 20;
  o.threads = static_cast<int>(state.range(0));
  const TestRunEvaluator evaluator(scene, backend, o.weights);
  int runs = 0;
  for (auto _ : state) {
    const PidTuningResult r = TunePid(evaluator, o);
    runs = r.test_runs;
    benchmark::DoNotOptimize(r.best_score.quality);
  }
  state.counters["test_runs"] = runs;
  state.counters["simulated_s_per_wall_s"] =
      benchmark::Counter(runs * scene.duration, benchmark::Counter::kIsIterationInvariantRate);
}

BENCHMARK_CAPTURE(BM_TenIterationsOfTwentyRuns, ode, std::string("ode"))
    ->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK_CAPTURE(BM_TenIterationsOfTwentyRuns, bullet, std::string("bullet"))
    ->Arg(2)->ArgName("threads")->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK_CAPTURE(BM_TenIterationsOfTwentyRuns, analytic, std::string("analytic"))
    ->Arg(2)->ArgName("threads")->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
