// twinsim batch: throughput of a sweep on 1 and 2 threads, and the runner's own cost
// per job (docs/benchmarks.md, docs/scaling.md).
//
//   build/batch_bench --benchmark_counters_tabular=true
//
// BM_BatchThroughput: 100 jobs of a 10 s omni scene (random driving, scenes/
// record_plant.yaml) on ODE per iteration; jobs_per_s is the sweep's throughput.
// BM_BatchOverhead: 200 jobs of a 0.1 s scene on the analytic engine (4 frames: next to
// no simulation), one thread; ms_per_job is what the runner costs per job (reading the
// scene and model, the job folder, trajectory.csv, truth.csv, result.json, the summary).
// The MPI comparison runs the CLI under mpirun: bench/batch_scaling.sh.
#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "batch/batch_runner.h"
#include "batch/sweep.h"
#include "io/atomic_file.h"

namespace twinsim {
namespace {

std::string BenchDir(const std::string& name) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("twinsim_batch_bench_" + name)).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

Sweep MakeSweep(const std::string& dir, const std::string& scene, const std::string& backend, double duration,
                int jobs) {
  const std::string path = dir + "/sweep.yaml";
  WriteFileAtomically(path, "name: bench\nseed: 1\ncommand: run\nfixed:\n  scene: " + std::string(TWINSIM_SOURCE_DIR) +
                                "/scenes/" + scene + "\n  scene.duration: " + std::to_string(duration) +
                                "\n  backend: " + backend + "\nrandom:\n  draws: " + std::to_string(jobs) +
                                "\n  parameters:\n    plant.chassis.mass: {uniform: [2.1, 2.5]}\n");
  return LoadSweep(path);
}

void RunOnce(const Sweep& sweep, const std::string& out, int threads) {
  std::filesystem::remove_all(out);
  BatchOptions options;
  options.out = out;
  options.jobs = threads;
  options.progress = false;
  RunBatch(sweep, options);
}

void BM_BatchThroughput(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int jobs = 100;
  const std::string dir = BenchDir("throughput");
  const Sweep sweep = MakeSweep(dir, "record_plant.yaml", "ode", 10.0, jobs);
  for (auto _ : state) RunOnce(sweep, dir + "/out", threads);
  state.counters["jobs_per_s"] = benchmark::Counter(jobs * state.iterations(), benchmark::Counter::kIsRate);
  state.SetLabel(std::to_string(threads) + " thread(s), ode, 10 s scenes");
}
BENCHMARK(BM_BatchThroughput)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

void BM_BatchOverhead(benchmark::State& state) {
  const int jobs = 200;
  const std::string dir = BenchDir("overhead");
  const Sweep sweep = MakeSweep(dir, "drive45.yaml", "analytic", 0.1, jobs);
  double seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    RunOnce(sweep, dir + "/out", 1);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  state.counters["ms_per_job"] = 1e3 * seconds / (jobs * static_cast<double>(state.iterations()));
  state.SetLabel("1 thread, analytic, 0.1 s scenes");
}
BENCHMARK(BM_BatchOverhead)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
