// twinsim's arm dynamics and MuJoCo's, side by side in one process and run (issue 31).
//
//   build/arm_mujoco_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Built only where MuJoCo was found at configure time (Debian: apt-get install
// libmujoco-dev). Both load the same URDF: the RRR arm (models/rrr.yaml, written out as
// URDF here) and the KUKA LWR4 of ../shared/realdata (skipped when absent), its meshes
// and visual geometry removed. MuJoCo is set to the physics twinsim's analytic backend
// computes: no contacts, no constraints (joint limits, friction loss), no passive forces
// (joint damping), gravity -9.81 z, 1 ms steps; twinsim's side has its joint friction
// off alike. Per arm:
//   InverseDynamics   twinsim InverseDynamics (RNEA)      vs mj_inverse
//   ForwardDynamics   twinsim ForwardDynamics (ABA)       vs mj_forward
//   StepRk4           the analytic backend's Step(1 ms)   vs mj_step, mjINT_RK4
//   StepEuler         SemiImplicitEulerStep (1 ms)        vs mj_step, mjINT_EULER
//   Accuracy          1 s of free swing from the same state with each integrator on
//                     both sides: the largest joint difference between the two, and
//                     each side's against twinsim's RK4 at 10 us (the truth up to 1e-12).
// After the run, a table of the ratios (MuJoCo's time over twinsim's) and the accuracy.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/rng.h"
#include "diagnosis/mujoco_arm_plant.h"
#include "diagnosis/mujoco_model.h"
#include "engines/arm_engine.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_integrators.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace {

using testing::ArmUrdf;

constexpr double kStep = 1e-3;  // s

// The KUKA's URDF without its meshes and visual or collision geometry (MuJoCo would look
// for the mesh files) and with one <origin> per joint, or "" when ../shared is absent.
std::string KukaUrdf() {
  const std::string path = std::string(TWINSIM_SOURCE_DIR) + "/../shared/realdata/kuka_lwr4/kuka_lwr4.urdf";
  std::ifstream in(path);
  if (!in) return "";
  std::stringstream text;
  text << in.rdbuf();
  const std::string bare = std::regex_replace(text.str(), std::regex("<(visual|collision)>[\\s\\S]*?</\\1>"), "");
  // Its fixed base joint lists two <origin>s; urdfdom takes the first, MuJoCo refuses.
  return std::regex_replace(bare, std::regex("(<origin[^>]*/>\\s*)<origin[^>]*/>"), "$1");
}

// One arm loaded on both sides from one URDF.
struct Arm {
  std::string name;
  ArmModel model;  // twinsim's, joint friction off
  std::unique_ptr<testing::MujocoModel> mujoco;
  Eigen::VectorXd q0, qd0, tau;  // a test state and a constant torque
};

std::unique_ptr<Arm> LoadArm(const std::string& name, const std::string& urdf) {
  auto arm = std::make_unique<Arm>();
  arm->name = name;
  arm->model = LoadArmModelFromUrdfString(urdf, name);
  for (ArmJoint& j : arm->model.joints) j.viscous = j.coulomb = 0;
  arm->mujoco = testing::LoadMujocoText(urdf, ".urdf", name);
  mjModel* m = arm->mujoco->model;
  const int n = arm->model.dof();
  if (m->nv != n) throw std::runtime_error(name + ": MuJoCo has " + std::to_string(m->nv) + " dof");
  m->opt.timestep = kStep;
  m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_CONSTRAINT | mjDSBL_PASSIVE;
  // The URDF's <dynamics damping friction>: off (mj_Euler would treat damping
  // implicitly even with passive forces disabled).
  for (int i = 0; i < n; ++i) m->dof_damping[i] = m->dof_frictionloss[i] = m->dof_armature[i] = 0;
  Rng rng(7);
  arm->q0.resize(n);
  arm->qd0.resize(n);
  arm->tau.resize(n);
  for (int i = 0; i < n; ++i) {
    arm->q0[i] = rng.Uniform(-1, 1);
    arm->qd0[i] = rng.Uniform(-1, 1);
    arm->tau[i] = rng.Uniform(-1, 1);
  }
  return arm;
}

// Both sides must compute the same physics: their inverse dynamics at the test state
// agree to 1e-9 relative, else the comparison would mean nothing.
void CheckSameModel(const Arm& arm) {
  const int n = arm.model.dof();
  Eigen::VectorXd qdd = Eigen::VectorXd::LinSpaced(n, -2, 2);
  std::copy_n(arm.q0.data(), n, arm.mujoco->data->qpos);
  std::copy_n(arm.qd0.data(), n, arm.mujoco->data->qvel);
  std::copy_n(qdd.data(), n, arm.mujoco->data->qacc);
  mj_inverse(arm.mujoco->model, arm.mujoco->data);
  const Eigen::VectorXd ours = InverseDynamics(arm.model, arm.q0, arm.qd0, qdd, false);
  const Eigen::VectorXd theirs = Eigen::Map<const Eigen::VectorXd>(arm.mujoco->data->qfrc_inverse, n);
  if ((ours - theirs).norm() > 1e-9 * ours.norm()) {
    std::ostringstream msg;
    msg << arm.name << ": twinsim and MuJoCo disagree on inverse dynamics: " << ours.transpose() << " vs "
        << theirs.transpose();
    throw std::runtime_error(msg.str());
  }
}

Arm* GetArm(int index) {
  static const std::unique_ptr<Arm> arms[2] = {
      LoadArm("rrr", ArmUrdf(LoadArmModel(std::string(TWINSIM_SOURCE_DIR) + "/models/rrr.yaml"))),
      KukaUrdf().empty() ? nullptr : LoadArm("kuka_lwr4", KukaUrdf())};
  static const bool checked = [] {
    for (const auto& a : arms)
      if (a) CheckSameModel(*a);
    return true;
  }();
  (void)checked;
  return arms[index].get();
}

// Sets MuJoCo's state to (q, qd) with the constant torque applied.
void SetMujocoState(const Arm& arm, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  const int n = arm.model.dof();
  mj_resetData(arm.mujoco->model, arm.mujoco->data);
  std::copy_n(q.data(), n, arm.mujoco->data->qpos);
  std::copy_n(qd.data(), n, arm.mujoco->data->qvel);
  std::copy_n(arm.tau.data(), n, arm.mujoco->data->qfrc_applied);
}

#define ARM_OR_SKIP(state)                                            \
  Arm* arm = GetArm(static_cast<int>(state.range(0)));                \
  if (!arm) return state.SkipWithError("no ../shared/realdata/kuka"); \
  state.SetLabel(arm->name)

void BM_Twinsim_InverseDynamics(benchmark::State& state) {
  ARM_OR_SKIP(state);
  Eigen::VectorXd q = arm->q0;
  const Eigen::VectorXd qdd = Eigen::VectorXd::Constant(arm->model.dof(), 0.5);
  for (auto _ : state) {
    benchmark::DoNotOptimize(InverseDynamics(arm->model, q, arm->qd0, qdd, false));
    q[0] += 1e-9;
  }
}

void BM_Mujoco_InverseDynamics(benchmark::State& state) {
  ARM_OR_SKIP(state);
  SetMujocoState(*arm, arm->q0, arm->qd0);
  std::fill_n(arm->mujoco->data->qacc, arm->mujoco->model->nv, 0.5);
  for (auto _ : state) {
    mj_inverse(arm->mujoco->model, arm->mujoco->data);
    benchmark::DoNotOptimize(arm->mujoco->data->qfrc_inverse[0]);
    arm->mujoco->data->qpos[0] += 1e-9;
  }
}

void BM_Twinsim_ForwardDynamics(benchmark::State& state) {
  ARM_OR_SKIP(state);
  Eigen::VectorXd q = arm->q0, qdd;
  for (auto _ : state) {
    ForwardDynamics(arm->model, q, arm->qd0, arm->tau, false, &qdd);
    benchmark::DoNotOptimize(qdd.data());
    q[0] += 1e-9;
  }
}

void BM_Mujoco_ForwardDynamics(benchmark::State& state) {
  ARM_OR_SKIP(state);
  SetMujocoState(*arm, arm->q0, arm->qd0);
  for (auto _ : state) {
    mj_forward(arm->mujoco->model, arm->mujoco->data);
    benchmark::DoNotOptimize(arm->mujoco->data->qacc[0]);
    arm->mujoco->data->qpos[0] += 1e-9;
  }
}

// Steps from the test state, starting over every simulated second so that both sides
// step the same stretch of motion.
constexpr int kStepsPerStart = 1000;

void BM_Twinsim_StepRk4(benchmark::State& state) {
  ARM_OR_SKIP(state);
  const std::unique_ptr<ArmEngine> engine = MakeArmEngine("analytic", arm->model);
  int k = 0;
  for (auto _ : state) {
    if (k++ % kStepsPerStart == 0) engine->Reset(arm->q0, arm->qd0);
    engine->Step(arm->tau, kStep);
  }
  benchmark::DoNotOptimize(engine->q().data());
}

void BM_Twinsim_StepEuler(benchmark::State& state) {
  ARM_OR_SKIP(state);
  Eigen::VectorXd q, qd;
  ArmStepWorkspace work;
  int k = 0;
  for (auto _ : state) {
    if (k++ % kStepsPerStart == 0) q = arm->q0, qd = arm->qd0;
    SemiImplicitEulerStep(arm->model, arm->tau, kStep, false, &work, &q, &qd);
  }
  benchmark::DoNotOptimize(q.data());
}

void MujocoStep(benchmark::State& state, int integrator) {
  ARM_OR_SKIP(state);
  arm->mujoco->model->opt.integrator = integrator;
  int k = 0;
  for (auto _ : state) {
    if (k++ % kStepsPerStart == 0) SetMujocoState(*arm, arm->q0, arm->qd0);
    mj_step(arm->mujoco->model, arm->mujoco->data);
  }
  benchmark::DoNotOptimize(arm->mujoco->data->qpos[0]);
}

void BM_Mujoco_StepRk4(benchmark::State& state) { MujocoStep(state, mjINT_RK4); }
void BM_Mujoco_StepEuler(benchmark::State& state) { MujocoStep(state, mjINT_EULER); }

// The largest joint difference (rad) between two trajectories of samples x n.
double MaxDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff(); }

// 1 s from the test state: positions after every step (1000 x n).
Eigen::MatrixXd TwinsimRun(const Arm& arm, bool rk4, double h) {
  const int per_ms = static_cast<int>(std::lround(kStep / h));
  Eigen::VectorXd q = arm.q0, qd = arm.qd0;
  ArmStepWorkspace work;
  Eigen::MatrixXd out(kStepsPerStart, arm.model.dof());
  for (int k = 0; k < kStepsPerStart; ++k) {
    for (int s = 0; s < per_ms; ++s) {
      if (rk4) Rk4Step(arm.model, arm.tau, h, false, &work, &q, &qd);
      else SemiImplicitEulerStep(arm.model, arm.tau, h, false, &work, &q, &qd);
    }
    out.row(k) = q.transpose();
  }
  return out;
}

Eigen::MatrixXd MujocoRun(const Arm& arm, int integrator) {
  arm.mujoco->model->opt.integrator = integrator;
  SetMujocoState(arm, arm.q0, arm.qd0);
  Eigen::MatrixXd out(kStepsPerStart, arm.model.dof());
  for (int k = 0; k < kStepsPerStart; ++k) {
    mj_step(arm.mujoco->model, arm.mujoco->data);
    out.row(k) = Eigen::Map<const Eigen::VectorXd>(arm.mujoco->data->qpos, arm.model.dof()).transpose();
  }
  return out;
}

void BM_Accuracy(benchmark::State& state) {
  ARM_OR_SKIP(state);
  const bool rk4 = state.range(1) == 1;
  state.SetLabel(arm->name + (rk4 ? " rk4" : " euler"));
  Eigen::MatrixXd ours, theirs;
  for (auto _ : state) {
    ours = TwinsimRun(*arm, rk4, kStep);
    theirs = MujocoRun(*arm, rk4 ? mjINT_RK4 : mjINT_EULER);
  }
  const Eigen::MatrixXd truth = TwinsimRun(*arm, true, 1e-5);
  state.counters["between_rad"] = MaxDifference(ours, theirs);
  state.counters["twinsim_err_rad"] = MaxDifference(ours, truth);
  state.counters["mujoco_err_rad"] = MaxDifference(theirs, truth);
}

BENCHMARK(BM_Twinsim_InverseDynamics)->DenseRange(0, 1);
BENCHMARK(BM_Mujoco_InverseDynamics)->DenseRange(0, 1);
BENCHMARK(BM_Twinsim_ForwardDynamics)->DenseRange(0, 1);
BENCHMARK(BM_Mujoco_ForwardDynamics)->DenseRange(0, 1);
BENCHMARK(BM_Twinsim_StepRk4)->DenseRange(0, 1);
BENCHMARK(BM_Mujoco_StepRk4)->DenseRange(0, 1);
BENCHMARK(BM_Twinsim_StepEuler)->DenseRange(0, 1);
BENCHMARK(BM_Mujoco_StepEuler)->DenseRange(0, 1);
BENCHMARK(BM_Accuracy)->ArgsProduct({{0, 1}, {0, 1}})->Iterations(1)->Unit(benchmark::kMillisecond);

// Collects each run's time per iteration (ns) under "what/arm", to print the ratios.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred || (run.run_type == Run::RT_Aggregate && run.aggregate_name != "mean")) continue;
      const std::string name = run.benchmark_name();
      const std::smatch m = Match(name);
      if (m.empty()) continue;
      // The mean where there are repetitions, else the single run.
      const std::string key = m[2].str() + "/" + m[3].str();
      if (run.run_type == Run::RT_Aggregate || !mean_seen_.count(m[1].str() + key)) {
        (m[1] == "Twinsim" ? twinsim_ : mujoco_)[key] = run.GetAdjustedRealTime();
        if (run.run_type == Run::RT_Aggregate) mean_seen_[m[1].str() + key] = true;
      }
    }
  }

  void PrintRatios() const {
    std::printf("\n%-26s %14s %14s %14s\n", "what/arm (0 rrr, 1 kuka)", "twinsim ns", "MuJoCo ns", "MuJoCo/twinsim");
    for (const auto& [key, ours] : twinsim_) {
      const auto theirs = mujoco_.find(key);
      if (theirs == mujoco_.end()) continue;
      std::printf("%-26s %14.1f %14.1f %14.2f\n", key.c_str(), ours, theirs->second, theirs->second / ours);
    }
  }

 private:
  static std::smatch Match(const std::string& name) {
    static const std::regex pattern("BM_(Twinsim|Mujoco)_([A-Za-z0-9]+)/([0-9]+)");
    std::smatch m;
    std::regex_search(name, m, pattern);
    return m;
  }
  std::map<std::string, double> twinsim_, mujoco_;
  std::map<std::string, bool> mean_seen_;
};

}  // namespace
}  // namespace twinsim

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  std::printf("MuJoCo %s\n", mj_versionString());
  twinsim::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.PrintRatios();
  benchmark::Shutdown();
  return 0;
}
