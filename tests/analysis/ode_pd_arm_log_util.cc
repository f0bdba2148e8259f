#include "analysis/ode_pd_arm_log.h"

#include <algorithm>
#include <cmath>

#include "backends/arm_backend_factory.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "sim/arm_simulation.h"

namespace twinsim::testing {

// A log of the RRR arm on ODE (another engine than the analytic one that scores it) under
// a PD with gravity feed-forward along a two-tone reference, the command updated every
// `hold` samples (the controller of a log sampled at 1 kHz / hold), recorded one row per
// update: t, q, q̇ as sampled, the torque sent. Read back through the CSV reader.
ArmLog OdePdArmLog(const ArmModel& plant, double seconds, int hold) {
  // t, q, q̇ and q̈ logged (no derived values, no edge rows).
  ArmSimulation sim(plant, MakeArmBackend("ode", plant));
  const Eigen::Vector3d centre(0.2, 0.4, -0.6), amplitude(0.5, 0.3, 0.6);
  auto reference = [&](double t) {
    Eigen::Vector3d q;
    for (int j = 0; j < 3; ++j)
      q[j] = centre[j] + amplitude[j] * (0.6 * std::sin(2 * kPi * 0.4 * (j + 1) * t) + 0.4 * std::sin(2 * kPi * 1.3 * t + j));
    return q;
  };
  sim.Reset(reference(0), Eigen::Vector3d::Zero());
  Eigen::VectorXd held;
  int k = 0;
  const ArmController pd = [&](double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    if (k++ % hold == 0) {
      const Eigen::VectorXd gravity = InverseDynamics(plant, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      held = gravity + 60.0 * (reference(t) - q) - 6.0 * qd;
    }
    return held;
  };
  const int samples = static_cast<int>(std::lround(seconds / plant.sample_time)) + 1;
  const ArmTrajectory run = sim.Run(samples, pd);
  const int rows = (samples - 1) / hold + 1;
  ArmLog log;
  log.dof = 3;
  log.t.resize(rows);
  log.q.resize(rows, 3);
  log.qd.resize(rows, 3);
  log.qdd.resize(rows, 3);
  log.tau.resize(rows, 3);
  for (int r = 0; r < rows; ++r) {
    log.t[r] = run.t[r * hold];
    log.q.row(r) = run.q.row(r * hold);
    log.qd.row(r) = run.qd.row(r * hold);
    log.tau.row(r) = run.command.row(r * hold);
  }
  // q̈ by central differences of the sampled q̇ (one-sided at the ends).
  const double dt = hold * plant.sample_time;
  for (int r = 0; r < rows; ++r) {
    const int a = std::max(r - 1, 0), b = std::min(r + 1, rows - 1);
    log.qdd.row(r) = (log.qd.row(b) - log.qd.row(a)) / ((b - a) * dt);
  }
  return ParseArmLog(FormatArmLog(log, true), "plant.csv");
}

}  // namespace twinsim::testing
