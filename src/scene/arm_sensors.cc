#include "scene/arm_sensors.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "io/csv_table.h"

namespace twinsim {
namespace {

// Joint j's torque noise is stream kTorqueNoiseStream + j of the scene's seed.
constexpr std::uint64_t kTorqueNoiseStream = 0x746e7300;  // "tns"

bool SizeOk(const Eigen::VectorXd& v, int dof) { return v.size() == 0 || v.size() == dof; }

bool AllFiniteNonNegative(const Eigen::VectorXd& v) {
  for (Eigen::Index j = 0; j < v.size(); ++j)
    if (!std::isfinite(v[j]) || v[j] < 0) return false;
  return true;
}

}  // namespace

bool ArmSensorSpec::IsIdeal() const {
  return log_velocities && (count_step.size() == 0 || count_step.isZero(0)) &&
         (torque_noise.size() == 0 || torque_noise.isZero(0));
}

bool ArmSensorSpec::IsValid(int dof, std::string* why) const {
  std::string problem;
  if (!SizeOk(count_step, dof) || !SizeOk(torque_noise, dof)) {
    problem = "count_step and torque_noise need " + std::to_string(dof) + " values (one per joint) or none";
  } else if (!AllFiniteNonNegative(count_step)) {
    problem = "count_step must be finite and >= 0";
  } else if (!AllFiniteNonNegative(torque_noise)) {
    problem = "torque_noise must be finite and >= 0";
  }
  if (why) *why = problem;
  return problem.empty();
}

ArmLog SensedArmLog(const ArmSensorSpec& sensors, const TrackingTrial& trial, std::uint64_t seed) {
  const int dof = static_cast<int>(trial.q.cols());
  std::string why;
  if (!sensors.IsValid(dof, &why)) throw InputError("SensedArmLog: " + why);
  ArmLog log;
  log.dof = dof;
  log.t = trial.t;
  log.q = trial.q;
  log.tau = trial.command;
  log.qref = trial.q_ref;
  log.sample_period = trial.sample_time;
  log.qd_logged = sensors.log_velocities;
  if (sensors.log_velocities) log.qd = trial.qd;

  const Eigen::Index rows = trial.t.size();
  for (int j = 0; j < sensors.count_step.size(); ++j) {
    const double step = sensors.count_step[j];
    if (step == 0) continue;
    for (Eigen::Index k = 0; k < rows; ++k) log.q(k, j) = std::round(trial.q(k, j) / step) * step;
  }
  // Drawn only for joints with noise, each from its own stream: turning one joint's
  // noise on or off leaves the others' bytes as they were.
  for (int j = 0; j < sensors.torque_noise.size(); ++j) {
    const double sigma = sensors.torque_noise[j];
    if (sigma == 0) continue;
    Rng rng = Rng::Derived(seed, kTorqueNoiseStream + static_cast<std::uint64_t>(j));
    for (Eigen::Index k = 0; k < rows; ++k) log.tau(k, j) += rng.Gaussian(sigma);
  }
  return log;
}

std::string FormatSensedArmLog(const ArmLog& log) {
  // The column order of the ideal log that came before the sensors: t, q, tau, qd, qref.
  std::vector<const char*> prefixes = {"q", "tau"};
  std::vector<const Eigen::MatrixXd*> columns = {&log.q, &log.tau};
  if (log.qd_logged) prefixes.push_back("qd"), columns.push_back(&log.qd);
  if (log.qref.size() > 0) prefixes.push_back("qref"), columns.push_back(&log.qref);
  return JointColumnsCsv(log.t, prefixes, columns);
}

}  // namespace twinsim
