// Identification speed (issue 5 goal): weighted least squares from 100 000 samples of a
// 7-joint arm in at most 2 s. The arm is the KUKA LWR4+ URDF from the real-data folder
// when present, else the RRR arm; the data is a synthetic multi-sine at 1 kHz (100 s)
// with quantised positions and noisy torques, velocities and accelerations derived by
// zero-phase filtering.
//
//   build/identification_bench
#include <benchmark/benchmark.h>

#include <filesystem>

#include "../tests/identification/synthetic_arm_data.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "signal/butterworth.h"

namespace twinsim {
namespace {

ArmModel BenchArm() {
  const std::string kuka = std::string(TWINSIM_SOURCE_DIR) + "/../shared/realdata/kuka_lwr4/kuka_lwr4.urdf";
  return LoadArmModel(std::filesystem::exists(kuka) ? kuka : std::string(TWINSIM_SOURCE_DIR) + "/models/rrr.yaml");
}

// 100 000 samples of an arm 15 % heavier than the model with 30 % more viscous
// friction, q-only, then read back as a file would be (qd, qdd derived).
const ArmLog& BenchLog(const ArmModel& arm) {
  static const ArmLog log = [&] {
    ArmModel truth = arm;
    for (auto& j : truth.joints) {
      j.child.mass *= 1.15;
      j.viscous *= 1.3;
    }
    testing::SensorNoise noise;
    noise.counts_per_rev = 1 << 18;
    noise.torque_fraction = 0.02;
    const ArmLog raw = testing::MakeSyntheticLog(truth, testing::MakeMultiSine(truth, 3, 5, 0.1, 0.6, 1.5), 99.999,
                                                 1000.0, noise);
    return ParseArmLog(FormatArmLog(raw, false), "bench.csv");
  }();
  return log;
}

void BM_IdentifyArm(benchmark::State& state) {
  const ArmModel arm = BenchArm();
  const ArmLog& log = BenchLog(arm);
  WlsIdentificationSummary summary;
  for (auto _ : state) benchmark::DoNotOptimize(IdentifyArmByLeastSquares(arm, {log}, {}, &summary));
  state.counters["joints"] = arm.dof();
  state.counters["samples"] = summary.samples;
  state.counters["base_params"] = static_cast<double>(summary.names.size());
  state.counters["cond"] = summary.condition_number;
  state.counters["fit_steps"] = summary.consistency_iterations;
}
BENCHMARK(BM_IdentifyArm)->Unit(benchmark::kMillisecond)->Iterations(3);

// The real KUKA run1 (5 027 samples at 200 Hz, logged qd and qdd) with torque offsets:
// its minimum-norm parameters are not physical, so this includes the consistent fit.
void BM_IdentifyKukaRun1(benchmark::State& state) {
  const std::string dir = std::string(TWINSIM_SOURCE_DIR) + "/../shared/realdata/kuka_lwr4";
  if (!std::filesystem::exists(dir + "/run1.csv")) {
    state.SkipWithError("no real data");
    return;
  }
  const ArmModel arm = LoadArmModel(dir + "/kuka_lwr4.urdf");
  const ArmLog log = ReadArmLog(dir + "/run1.csv");
  WlsIdentificationOptions options;
  options.torque_offsets = true;
  WlsIdentificationSummary summary;
  for (auto _ : state) benchmark::DoNotOptimize(IdentifyArmByLeastSquares(arm, {log}, options, &summary));
  state.counters["samples"] = summary.samples;
  state.counters["fit_steps"] = summary.consistency_iterations;
}
BENCHMARK(BM_IdentifyKukaRun1)->Unit(benchmark::kMillisecond)->Iterations(3);

// Deriving qd and qdd of 7 joints x 100 000 samples (filter, then differences).
void BM_DeriveVelocities(benchmark::State& state) {
  const ArmModel arm = BenchArm();
  const ArmLog& log = BenchLog(arm);
  const ButterworthFilter filter = DesignButterworthLowPass(4, 10, 1000);
  for (auto _ : state) {
    for (int j = 0; j < log.dof; ++j) benchmark::DoNotOptimize(FilteredDerivatives(filter, log.t, log.q.col(j)));
  }
  state.counters["samples"] = log.rows();
}
BENCHMARK(BM_DeriveVelocities)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
