// Speed and accuracy of the learned arm model (issue 5, last section):
//   training on 60 s of 1 kHz trials (linear, neural, each also as a residual over the
//   nominal model), one prediction, the learned
//   backend's real-time factor in the whole loop, and the writing-task comparison with
//   the full-size network (printed; docs/arm_learning.md records it).
//
//   build/arm_learning_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>

#include "analysis/arm_model_comparison.h"
#include "backends/arm_backend_factory.h"
#include "backends/learned/learned_arm_backend.h"
#include "control/arm_trials.h"
#include "control/writing_task.h"
#include "sim/arm_simulation.h"

namespace twinsim {
namespace {

const ArmModel& Plant() {
  static const ArmModel m = LoadArmModel(std::string(TWINSIM_SOURCE_DIR) + "/models/rrr_plant.yaml");
  return m;
}
const ArmModel& Hat() {
  static const ArmModel m = LoadArmModel(std::string(TWINSIM_SOURCE_DIR) + "/models/rrr.yaml");
  return m;
}

// 60 s of trials on the plant at 1 kHz: three 20 s trials (two multi-sine, one stop-and-go).
const std::vector<ArmLog>& Trials() {
  static const std::vector<ArmLog> logs = RecordTrainingTrials(Plant(), Hat(), TrainingTrialOptions{}, 3, 1);
  return logs;
}

// The same length with two of the three trials stop-and-go (the test suite's mix): the
// writing task stops at every corner, where friction acts.
const std::vector<ArmLog>& StopAndGoTrials() {
  static const std::vector<ArmLog> logs = [] {
    TrainingTrialOptions options;
    options.stop_and_go = 0.67;
    return RecordTrainingTrials(Plant(), Hat(), options, 3, 1);
  }();
  return logs;
}

// The learned models by name: "linear", "mlp", "residual linear", "residual mlp", the
// residual ones with the other choice of nominal-error inputs ("... +errors",
// "... -errors"; docs/arm_learning.md), and any of them trained on StopAndGoTrials()
// ("..., 2/3 stop-and-go").
ArmTrainOptions OptionsFor(const std::string& name) {
  ArmTrainOptions options;
  options.kind = name.find("mlp") != std::string::npos ? "mlp" : "linear";
  options.residual = name.rfind("residual", 0) == 0;
  if (name.find("+errors") != std::string::npos) options.nominal_errors = true;
  if (name.find("-errors") != std::string::npos) options.nominal_errors = false;
  return options;
}

const ArmPredictor& Trained(const std::string& name) {
  static std::map<std::string, ArmPredictor> cache;
  auto it = cache.find(name);
  if (it == cache.end()) {
    ArmTrainSummary summary;
    const bool stop_and_go = name.find("stop-and-go") != std::string::npos;
    it = cache.emplace(name, TrainArmPredictor(Hat(), stop_and_go ? StopAndGoTrials() : Trials(), OptionsFor(name),
                                               &summary))
             .first;
    std::fprintf(stderr, "[%s] %s\n", name.c_str(), summary.BriefReport().c_str());
  }
  return it->second;
}

const std::vector<std::string> kLearned = {"linear",
                                           "mlp",
                                           "residual linear",
                                           "residual mlp",
                                           "residual linear -errors",
                                           "residual mlp +errors",
                                           "linear, 2/3 stop-and-go",
                                           "mlp, 2/3 stop-and-go",
                                           "residual linear, 2/3 stop-and-go",
                                           "residual mlp, 2/3 stop-and-go"};

void BM_ArmTrain(benchmark::State& state) {
  const std::string name = kLearned[static_cast<std::size_t>(state.range(0))];
  state.SetLabel(name + ", 60 s at 1 kHz, history 4");
  Trials();
  for (auto _ : state) {
    ArmTrainSummary summary;
    benchmark::DoNotOptimize(TrainArmPredictor(Hat(), Trials(), OptionsFor(name), &summary));
    std::fprintf(stderr, "[%s] %s\n", name.c_str(), summary.BriefReport().c_str());
  }
}
BENCHMARK(BM_ArmTrain)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_ArmPredict(benchmark::State& state) {
  const std::string name = kLearned[static_cast<std::size_t>(state.range(0))];
  state.SetLabel(name);
  const ArmPredictor& p = Trained(name);
  double q[12], qd[12], tau[12], qn[3], qdn[3];
  for (int i = 0; i < 12; ++i) q[i] = 0.1 * i, qd[i] = 0.2, tau[i] = 1;
  // The newest state changes every call, as in the loop: a residual predictor's nominal
  // step from it is new, its steps over the older transitions are remembered.
  double nudge = 0;
  for (auto _ : state) {
    q[9] = 0.9 + (nudge += 1e-12);
    p.Predict(q, qd, tau, qn, qdn);
    benchmark::DoNotOptimize(qn);
  }
}
BENCHMARK(BM_ArmPredict)->DenseRange(0, 3);

// The whole loop (delay line, controller, backend) for 1 s of simulated time.
void BM_ArmLoop(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const std::string name = which == 4 ? "physical analytic" : "learned " + kLearned[static_cast<std::size_t>(which)];
  state.SetLabel(name);
  const ArmModel& hat = Hat();
  auto backend = which == 4 ? MakeArmBackend("analytic", hat)
                            : MakeLearnedArmBackend(hat, Trained(kLearned[static_cast<std::size_t>(which)]));
  ArmSimulation sim(hat, std::move(backend));
  const Eigen::VectorXd q0 = Eigen::Vector3d(0, 0.35, -1.1);
  const ArmController pd = [&](double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    return Eigen::VectorXd(60 * (q0 + Eigen::Vector3d::Constant(0.2 * std::sin(3 * t)) - q) - 6 * qd +
                           Eigen::Vector3d(0, 10, 2));
  };
  for (auto _ : state) {
    sim.Reset(q0, Eigen::VectorXd::Zero(3));
    benchmark::DoNotOptimize(sim.Run(1000, pd));
  }
  state.counters["real_time_factor"] =
      benchmark::Counter(1.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ArmLoop)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

// The comparison with the full-size network, printed once.
void BM_WritingComparison(benchmark::State& state) {
  const ArmModel& hat = Hat();
  const ArmReference ref = WritingTaskReference(hat, WritingTaskOptions{});
  std::vector<ArmCandidate> candidates;
  for (const std::string& b : AvailableArmEngines())
    candidates.push_back({"physical nominal (" + b + ")", hat, [&, b] { return MakeArmBackend(b, hat); }});
  for (const std::string& name : kLearned)
    candidates.push_back({"learned " + name, hat, [&, name] { return MakeLearnedArmBackend(hat, Trained(name)); }});
  for (auto _ : state) {
    const WritingComparison c = CompareOnReference(Plant(), hat, ref, candidates, TrackingOptions{});
    std::fprintf(stderr, "writing task against the plant:\n%s", c.FullReport().c_str());
  }
  // Open loop on a held-out trial (seed 100, stop-and-go), 100 ms.
  TrainingTrialOptions held;
  const ArmLog test = RecordTrainingTrials(Plant(), hat, held, 2, 100)[1];
  auto row = [](const char* name, const RolloutStats& s) {
    std::fprintf(stderr, "open loop %-26s one step (urad) %.3f %.3f %.3f | 100 ms RMS (mrad) %.3f %.3f %.3f\n", name,
                 s.one_step_rms[0] * 1e6, s.one_step_rms[1] * 1e6, s.one_step_rms[2] * 1e6, s.final_rms[0] * 1e3,
                 s.final_rms[1] * 1e3, s.final_rms[2] * 1e3);
  };
  for (const std::string& name : kLearned)
    row(name.c_str(), PredictorRolloutStats(Trained(name), test, 10, test.rows() - 1, 100, 250));
  row("physical nominal", PhysicalRolloutStats(hat, "analytic", test, 10, test.rows() - 1, 100, 250));
}
BENCHMARK(BM_WritingComparison)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
