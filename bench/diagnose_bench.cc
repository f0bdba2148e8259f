// Diagnosis speed (issue 11 goal): a 60 s log (arm at 1 kHz, omni at 30 fps) diagnosed
// in at most 30 s on this 2-core machine, with the default DiagnosisOptions.
//
//   build/diagnose_bench --benchmark_counters_tabular=true
//
// BM_DiagnoseArm: the RRR arm (models/rrr.yaml) as the nominal model; the plant is the
// same arm with a hidden coulomb_friction on joint 3 (c_pos 0.6, c_neg 0.3 N·m). One
// 60 s multi-sine tracking run at 1 kHz (computed torque, no dither), q quantised to
// 2e5 counts per revolution, 0.02 N·m Gaussian noise on the logged torques, then read
// back as a file would be (q and tau only: qd, qdd derived).
// BM_DiagnoseOmni: models/omni4.yaml as the nominal model; the plant has a hidden
// traction_limit (a_max 1.2 m/s^2). One 60 s random drive at 30 fps (≤ 1.5 m/s,
// ≤ 3 m/s^2 centripetal, leash 1.5 m) with the camera's noise (1 mm, 0.005 rad),
// replayed by the analytic backend (the default) or by ODE.
// The logs are recorded once, outside the timed loop; each case runs once (wall time,
// the diagnosis runs its candidates on every core). Counters: the gaps before and after
// (held-out, the report's metric), the effects added, the log's rows; the label names
// the effects and their fitted parameters.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "backends/omni_backend_factory.h"
#include "control/arm_trials.h"
#include "core/math_constants.h"
#include "diagnosis/arm_diagnosis.h"
#include "diagnosis/omni_diagnosis.h"
#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "scene/command_source.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "sim/omni_simulation.h"

namespace twinsim {
namespace {

constexpr double kSeconds = 60;  // s, length of each log

std::string Source(const std::string& relative) { return std::string(TWINSIM_SOURCE_DIR) + "/" + relative; }

// "coulomb_friction (joint 3) c_neg=0.3 c_pos=0.6; ...": the effects a report added.
std::string Named(const DiagnosisReport& report) {
  std::string s;
  for (const DiagnosedEffect& e : report.effects) {
    s += (s.empty() ? "" : "; ") + EffectLabel(e.name, e.joint);
    for (const auto& [key, value] : e.parameters) s += " " + key + "=" + FormatParameter(value);
  }
  return s.empty() ? "nothing" : s;
}

void ReportCounters(benchmark::State& state, const DiagnosisReport& report, double rows) {
  state.counters["rows"] = rows;
  state.counters["gap_before"] = report.gap_before;
  state.counters["gap_after"] = report.gap_after;
  state.counters["noise_floor"] = report.noise_floor;
  state.counters["effects"] = static_cast<double>(report.effects.size());
  state.counters["candidates"] = static_cast<double>(report.candidates.size());
  state.SetLabel(Named(report));
}

// The arm log: 60 s of the RRR plant with its hidden Coulomb friction on joint 3.
const ArmLog& ArmBenchLog(const ArmModel& hat) {
  static const ArmLog log = [&] {
    ArmModel plant = hat;
    ArmEffect friction;
    friction.name = "coulomb_friction";
    friction.joint = 2;  // joint 3
    friction.parameters = {{"c_pos", 0.6}, {"c_neg", 0.3}};
    AddArmEffect(friction, plant.dof(), &plant.effects);

    const std::uint64_t seed = 1;
    TrainingTrialOptions options;
    options.seconds = kSeconds;
    options.dither = 0;  // a dither's fast response is lost to the derivative filter
    const ArmReference reference =
        SampledReference(RandomTrainingTrajectory(hat, options, seed), hat.sample_time, kSeconds);
    ArmLog raw = RecordArmTrial(plant, hat, reference, options, seed);

    std::mt19937_64 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const double count = 2 * kPi / 2e5;  // rad, one encoder count
    for (int r = 0; r < raw.rows(); ++r) {
      for (int j = 0; j < raw.dof; ++j) {
        raw.q(r, j) = std::round(raw.q(r, j) / count) * count;
        raw.tau(r, j) += 0.02 * gauss(rng);  // N·m
      }
    }
    return ParseArmLog(FormatArmLog(raw, false), "arm_bench.csv");
  }();
  return log;
}

void BM_DiagnoseArm(benchmark::State& state) {
  const ArmModel hat = LoadArmModel(Source("models/rrr.yaml"));
  const ArmLog& log = ArmBenchLog(hat);
  DiagnosisReport report;
  for (auto _ : state) report = DiagnoseArm(hat, {log}, DiagnosisOptions{});
  ReportCounters(state, report, log.rows());
}
BENCHMARK(BM_DiagnoseArm)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// The omni log: 60 s of omni4 with its hidden traction limit, as the camera saw it.
const OmniLog& OmniBenchLog(const OmniModel& nominal) {
  static const OmniLog log = [&] {
    OmniModel plant = nominal;
    plant.effects.a_max = 1.2;  // m/s^2
    plant.vision_noise_xy = 0.001;
    plant.vision_noise_theta = 0.005;
    CommandSpec drive;
    drive.type = "random";
    drive.max_speed = 1.5;
    drive.max_centripetal = 3;
    drive.leash = 1.5;
    const std::uint64_t seed = 5;
    std::vector<SimRobot> robots;
    robots.push_back(SimRobot{"r", plant, Pose2{}, MakeCommandSource(drive, seed, 0, kSeconds, Pose2{})});
    Simulation sim(std::move(robots), MakeOmniBackend("analytic", {plant}, FieldModel{}, FrameTiming{}), seed);
    const SimulationResult result = sim.Run(static_cast<int>(kSeconds * FrameTiming{}.frame_rate) + 1);
    return ParseOmniLog(FormatOmniLog(ObserverLog(result.frames[0])), "omni_bench.csv");
  }();
  return log;
}

void BM_DiagnoseOmni(benchmark::State& state, const std::string& backend) {
  const OmniModel nominal = LoadOmniModel(Source("models/omni4.yaml"));
  const OmniLog& log = OmniBenchLog(nominal);
  DiagnosisOptions options;
  options.backend = backend;
  DiagnosisReport report;
  for (auto _ : state) {
    try {
      report = DiagnoseOmni(nominal, {log}, options);
    } catch (const std::exception& e) {
      state.SkipWithError(e.what());  // e.g. a backend that was not built
      return;
    }
  }
  ReportCounters(state, report, static_cast<double>(log.rows.size()));
}
BENCHMARK_CAPTURE(BM_DiagnoseOmni, analytic, std::string("analytic"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_DiagnoseOmni, ode, std::string("ode"))->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Issue 27's goal: identification plus diagnosis of a 60 s log in at most 60 s. The log:
// a minute of scenes/record_real_like.yaml (models/omni4_real_like.yaml on ODE at 60 Hz,
// 7 % repeated frames, 1 ms time-stamp jitter); `diagnose --refit-model` from
// models/omni4.yaml identifies the response on the fit blocks, then seeks effects.
void BM_IdentifyAndDiagnoseOmni(benchmark::State& state) {
  const OmniModel nominal = LoadOmniModel(Source("models/omni4.yaml"));
  static const OmniLog log = [&] {
    const Scene scene = LoadScene(Source("scenes/record_real_like.yaml"));
    const SimulationResult r = RunOmniScene(scene, scene.backend, "");
    return ParseOmniLog(FormatOmniLog(ObserverLog(r.frames[0])), "real_like_bench.csv");
  }();
  DiagnosisOptions options;
  options.refit_model = true;
  DiagnosisReport report;
  for (auto _ : state) report = DiagnoseOmni(nominal, {log}, options);
  ReportCounters(state, report, static_cast<double>(log.rows.size()));
  state.counters["refit_gap"] = report.refit_gap;
}
BENCHMARK(BM_IdentifyAndDiagnoseOmni)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
