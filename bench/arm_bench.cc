// Arm dynamics speed (issue 5 goals): inverse dynamics of a 7-joint arm <= 2 us.
//
//   build/arm_bench
#include <benchmark/benchmark.h>

#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {
namespace {

// A 7-joint chain shaped like a KUKA LWR4 (alternating axes, 0.4 m links).
ArmModel SevenJoints() {
  ArmModel m;
  for (int i = 0; i < 7; ++i) {
    ArmJoint j;
    j.origin = Eigen::Isometry3d::Identity();
    j.origin.translate(Eigen::Vector3d(0, 0, i % 2 ? 0.2 : 0.0));
    j.origin.rotate(Eigen::AngleAxisd(i % 2 ? kPi / 2 : -kPi / 2, Eigen::Vector3d::UnitX()));
    j.child.mass = 2.0;
    j.child.com = Eigen::Vector3d(0, 0.02, 0.1);
    j.child.inertia = Eigen::Vector3d(0.02, 0.02, 0.005).asDiagonal();
    j.viscous = 0.5;
    j.coulomb = 1.0;
    m.joints.push_back(j);
  }
  return m;
}

void BM_InverseDynamics7(benchmark::State& state) {
  const ArmModel m = SevenJoints();
  Rng rng(1);
  Eigen::VectorXd q(7), qd(7), qdd(7);
  for (int i = 0; i < 7; ++i) q[i] = rng.Uniform(-2, 2), qd[i] = rng.Uniform(-1, 1), qdd[i] = rng.Uniform(-3, 3);
  for (auto _ : state) {
    benchmark::DoNotOptimize(InverseDynamics(m, q, qd, qdd));
    q[0] += 1e-9;
  }
}
BENCHMARK(BM_InverseDynamics7)->Unit(benchmark::kMicrosecond);

void BM_Regressor7(benchmark::State& state) {
  const ArmModel m = SevenJoints();
  Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3), qd = Eigen::VectorXd::Constant(7, 0.2),
                  qdd = Eigen::VectorXd::Constant(7, 1.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(Regressor(m, q, qd, qdd));
    q[0] += 1e-9;
  }
}
BENCHMARK(BM_Regressor7)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
