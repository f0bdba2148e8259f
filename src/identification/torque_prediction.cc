#include "identification/torque_prediction.h"

#include <cmath>
#include <limits>

#include "robots/arm/arm_dynamics.h"

namespace twinsim {

Eigen::MatrixXd PredictArmTorques(const ArmModel& model, const ArmLog& log) {
  CheckArmLogMatchesModel(log, model);
  Eigen::MatrixXd tau(log.rows(), log.dof);
  for (int r = 0; r < log.rows(); ++r) {
    tau.row(r) = InverseDynamics(model, log.q.row(r).transpose(), log.qd.row(r).transpose(),
                                 log.qdd.row(r).transpose(), true)
                     .transpose();
  }
  return tau;
}

Eigen::MatrixXd PredictBaseTorques(const ArmModel& model, const BaseParameters& base, const Eigen::VectorXd& beta,
                                   const ArmLog& log) {
  CheckArmLogMatchesModel(log, model);
  Eigen::MatrixXd tau(log.rows(), log.dof);
  for (int r = 0; r < log.rows(); ++r) {
    const Eigen::MatrixXd y = Regressor(model, log.q.row(r).transpose(), log.qd.row(r).transpose(),
                                        log.qdd.row(r).transpose());
    tau.row(r) = (base.Reduce(y) * beta).transpose();
  }
  return tau;
}

TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, int first, int last) {
  return CompareArmTorques(model, log, PredictArmTorques(model, log), first, last);
}

TorqueErrors CompareArmTorques(const ArmModel& model, const ArmLog& log, const Eigen::MatrixXd& predicted,
                               int first, int last) {
  CheckArmLogMatchesModel(log, model);
  if (last < 0 || last > log.rows()) last = log.rows();
  if (first < 0) first = 0;
  const int rows = std::max(0, last - first);
  TorqueErrors e;
  e.rows = rows;
  const int n = log.dof;
  e.error_rms = Eigen::VectorXd::Zero(n);
  e.torque_rms = Eigen::VectorXd::Zero(n);
  e.relative = Eigen::VectorXd::Zero(n);
  if (rows == 0) return e;
  const auto measured = log.tau.middleRows(first, rows);
  const auto model_tau = predicted.middleRows(first, rows);
  double normalised = 0;
  for (int j = 0; j < n; ++j) {
    e.error_rms[j] = std::sqrt((measured.col(j) - model_tau.col(j)).squaredNorm() / rows);
    e.torque_rms[j] = std::sqrt(measured.col(j).squaredNorm() / rows);
    e.relative[j] = e.torque_rms[j] > 0 ? e.error_rms[j] / e.torque_rms[j] : 0.0;
    const double limit = model.joints[static_cast<std::size_t>(j)].effort_limit;
    normalised += limit > 0 ? e.error_rms[j] / (2 * limit) : std::numeric_limits<double>::quiet_NaN();
  }
  e.normalised = normalised / n;
  return e;
}

}  // namespace twinsim
