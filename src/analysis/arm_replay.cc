#include "analysis/arm_replay.h"

#include <cmath>
#include <limits>

#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {
namespace {

// Second derivative of x over the (nearly uniform) times t by three-point differences;
// the end rows take their neighbour's value.
Eigen::VectorXd SecondDerivative(const Eigen::VectorXd& t, const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
  if (n < 3) return d;
  for (Eigen::Index r = 1; r + 1 < n; ++r) {
    const double h1 = t[r] - t[r - 1], h2 = t[r + 1] - t[r];
    d[r] = 2 * (h1 * x[r + 1] - (h1 + h2) * x[r] + h2 * x[r - 1]) / (h1 * h2 * (h1 + h2));
  }
  d[0] = d[1];
  d[n - 1] = d[n - 2];
  return d;
}

}  // namespace

Eigen::VectorXd ShiftEarlier(const Eigen::VectorXd& t, const Eigen::VectorXd& x, double shift) {
  if (shift <= 0) return x;
  const Eigen::Index n = x.size();
  Eigen::VectorXd y(n);
  Eigen::Index i = 0;
  for (Eigen::Index r = 0; r < n; ++r) {
    const double when = t[r] + shift;
    while (i + 1 < n && t[i + 1] <= when) ++i;
    if (i + 1 >= n) {
      y[r] = x[n - 1];
    } else {
      const double a = (when - t[i]) / (t[i + 1] - t[i]);
      y[r] = (1 - a) * x[i] + a * x[i + 1];
    }
  }
  return y;
}

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

double JointCommandLead(const ArmModel& model, int joint) {
  return model.delay_samples * model.sample_time + model.effects.joint(joint).time_delay;
}

Eigen::VectorXd JointCommandFromNeeded(const ArmModel& model, int joint, const Eigen::VectorXd& t,
                                       const Eigen::VectorXd& qdd, Eigen::VectorXd drive, int* beyond_saturation) {
  const JointEffects e = model.effects.joint(joint);
  const Eigen::Index rows = drive.size();
  // 2. A flexible joint: the spring carries `needed`; the motor must also accelerate.
  if (e.flexible() && rows > 0) {
    Eigen::VectorXd deflection(rows);
    deflection[0] = drive[0] / e.stiffness;
    for (Eigen::Index r = 1; r < rows; ++r) {
      if (e.flex_damping > 0) {
        const double h = t[r] - t[r - 1];
        deflection[r] = (deflection[r - 1] + h / e.flex_damping * drive[r]) / (1 + h * e.stiffness / e.flex_damping);
      } else {
        deflection[r] = drive[r] / e.stiffness;
      }
    }
    drive += e.motor_inertia * (qdd + SecondDerivative(t, deflection));
  }
  // 3. The joint receives the command plus the offset.
  drive.array() -= e.torque_offset;
  // 4. Saturation cannot be inverted: count what no command within the limit gives.
  if (beyond_saturation) {
    *beyond_saturation = e.saturation > 0 ? static_cast<int>((drive.array().abs() > e.saturation).count()) : 0;
  }
  // 5. Sent `shift` seconds before the joint gets it.
  return ShiftEarlier(t, drive, JointCommandLead(model, joint));
}

Eigen::MatrixXd PredictArmCommands(const ArmModel& model, const ArmLog& log, ArmCommandSummary* summary) {
  CheckArmLogMatchesModel(log, model);
  const int n = log.dof;
  const ArmModel bodies = ArmPlantModel(model);  // the payload lumped into the last link
  // 1. What the links need: rigid bodies and all friction.
  Eigen::MatrixXd needed(log.rows(), n);
  for (int r = 0; r < log.rows(); ++r) {
    const Eigen::VectorXd qd = log.qd.row(r).transpose();
    needed.row(r) = InverseDynamics(bodies, log.q.row(r).transpose(), qd, log.qdd.row(r).transpose(), false).transpose();
  }
  for (int j = 0; j < n; ++j) {
    needed.col(j) += ArmFrictionAlong(model, j, log.t, log.q.col(j), log.qd.col(j));
    // position_torque acts on the link: the drive needs that much less.
    const JointEffects e = model.effects.joint(j);
    if (e.torque_profile.on()) needed.col(j) -= log.q.col(j).unaryExpr([&e](double q) { return e.PositionTorque(q); });
  }
  ArmCommandSummary s;
  s.shift.resize(n);
  s.beyond_saturation = Eigen::VectorXi::Zero(n);
  Eigen::MatrixXd command(log.rows(), n);
  for (int j = 0; j < n; ++j) {
    command.col(j) = JointCommandFromNeeded(model, j, log.t, log.qdd.col(j), needed.col(j), &s.beyond_saturation[j]);
    s.shift[j] = JointCommandLead(model, j);
    s.flexible = s.flexible || model.effects.joint(j).flexible();
  }
  if (summary) *summary = s;
  return command;
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
  return CompareArmTorques(model, log, PredictArmCommands(model, log), first, last);
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
