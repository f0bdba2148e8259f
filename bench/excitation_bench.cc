// Excitation design and batch-adaptive trials for the RRR arm (issue 5 goal: the
// default design, 8 starts on this 2-core machine, in at most 60 s).
//
//   build/excitation_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "core/math_constants.h"
#include "identification/batch_adaptive.h"
#include "identification/excitation_design.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace {

const ArmModel& Rrr() {
  static const ArmModel m = LoadArmModel(TWINSIM_SOURCE_DIR "/models/rrr.yaml");
  return m;
}

// The default design of `twinsim excite`: 5 harmonics of 0.1 Hz, 200 samples per
// period, 8 starts of 4 penalty rounds x 100 LBFGS iterations, 2 threads.
void BM_DesignExcitationRrr(benchmark::State& state) {
  ExcitationOptions o;
  o.threads = static_cast<int>(state.range(0));
  ExcitationSummary s;
  for (auto _ : state) benchmark::DoNotOptimize(DesignExcitation(Rrr(), o, &s));
  state.counters["cond_random_median"] = s.random_condition_median;
  state.counters["cond_start"] = s.start_condition;
  state.counters["cond_final"] = s.final_condition;
  state.counters["cond_final_unscaled"] = s.final_condition_unscaled;
  state.counters["iterations"] = s.iterations;
}
BENCHMARK(BM_DesignExcitationRrr)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// One evaluation of the criterion and its gradient (200 samples, 21 parameters).
void BM_ExcitationObjectiveAndGradient(benchmark::State& state) {
  const ExcitationOptions o;
  const FourierTrajectory t = RandomFeasibleExcitation(Rrr(), o, 3);
  FourierTrajectory g;
  for (auto _ : state) benchmark::DoNotOptimize(EvaluateExcitationObjective(Rrr(), o, t, 100, &g));
}
BENCHMARK(BM_ExcitationObjectiveAndGradient)->Unit(benchmark::kMillisecond);

// One simulated trial: 10 s at 1 kHz, RK4 on the RRR's forward dynamics, PD feedback.
void BM_SimulatedTrial(benchmark::State& state) {
  const ExcitationOptions o;
  const FourierTrajectory t = RandomFeasibleExcitation(Rrr(), o, 3);
  const SampledMotion s = SampleFourier(t, 0.001, t.period());
  ArmTrialInput in;
  in.q_ref = s.q;
  in.qd_ref = s.qd;
  in.feedforward = Eigen::MatrixXd::Zero(s.q.rows(), 3);
  in.hold_command = Eigen::VectorXd::Zero(3);
  in.kp = Eigen::VectorXd::Constant(3, 1000);
  in.kd = Eigen::VectorXd::Constant(3, 20);
  for (auto _ : state) benchmark::DoNotOptimize(RunTrial(Rrr(), in, {}));
}
BENCHMARK(BM_SimulatedTrial)->Unit(benchmark::kMillisecond);

// Batch-adaptive estimation on the test plant (tests/identification/rrr_plant.yaml)
// along the default design; arg 1 adds 16-bit encoders and 0.1 N·m torque noise. The
// counters: trials to converge (tolerance 1e-5 without noise, 2e-3 with), the worst
// base parameter's error relative to its own value, and relative to
// max(own value, 5 % of the largest typical torque contribution) as the tests judge it.
void BM_BatchAdaptiveRecovery(benchmark::State& state) {
  static const FourierTrajectory design = DesignExcitation(Rrr(), ExcitationOptions{});
  static const ArmModel plant = LoadArmModel(TWINSIM_SOURCE_DIR "/tests/identification/rrr_plant.yaml");
  const bool noisy = state.range(0) == 1;
  ArmTrialOptions p;
  BatchAdaptiveOptions o;
  o.tolerance = 1e-5;
  if (noisy) {
    p.encoder_resolution = 2 * kPi / 65536;
    p.torque_noise = Eigen::VectorXd::Constant(3, 0.1);
    o.tolerance = 2e-3;
  }
  BatchAdaptiveResult r;
  for (auto _ : state) r = RunBatchAdaptive(Rrr(), design, o, SimulatedTrials(plant, p));
  const Eigen::VectorXd truth = r.base.from_standard * StandardParameters(plant);
  const Eigen::VectorXd scales = ExcitationColumnScales(Rrr(), r.base, ResolveExcitationLimits(Rrr(), {}));
  const double floor = 0.05 * scales.cwiseProduct(truth).cwiseAbs().maxCoeff();
  double worst = 0, worst_own = 0;
  for (int c = 0; c < truth.size(); ++c) {
    const double e = std::abs(r.beta[c] - truth[c]);
    worst = std::max(worst, scales[c] * e / std::max(scales[c] * std::abs(truth[c]), floor));
    worst_own = std::max(worst_own, e / std::abs(truth[c]));
  }
  state.counters["trials"] = static_cast<double>(r.trials.size());
  state.counters["converged"] = r.converged;
  state.counters["worst_err_pct"] = 100 * worst;
  state.counters["worst_own_pct"] = 100 * worst_own;
  state.counters["rms_first_mrad"] = 1e3 * r.trials.front().error_rms.maxCoeff();
  state.counters["rms_last_mrad"] = 1e3 * r.trials.back().error_rms.maxCoeff();
}
BENCHMARK(BM_BatchAdaptiveRecovery)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
