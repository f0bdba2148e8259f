#include "learning/arm_features.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "learning/arm_nominal_step.h"

namespace twinsim {

int ArmFeatureLayout::per_sample() const {
  int n = 0;
  for (char c : joints) n += c == 'R' ? 2 : 1;
  return n + 2 * dof();
}

ArmFeatureLayout ArmLayoutFor(const ArmModel& model, int history, int horizon) {
  ArmFeatureLayout layout;
  for (const ArmJoint& j : model.joints) layout.joints += j.type == JointType::kRevolute ? 'R' : 'P';
  layout.history = history;
  layout.horizon = horizon;
  layout.command_lag = model.delay_samples;
  layout.sample_time = model.sample_time;
  return layout;
}

void EncodeArmInputs(const ArmFeatureLayout& layout, const double* q, const double* qd, const double* tau,
                     double* out) {
  const int n = layout.dof();
  for (int j = 0; j < layout.history; ++j) {
    const double* qj = q + j * n;
    for (int i = 0; i < n; ++i) {
      if (layout.joints[static_cast<std::size_t>(i)] == 'R') {
        *out++ = std::sin(qj[i]);
        *out++ = std::cos(qj[i]);
      } else {
        *out++ = qj[i];
      }
    }
    for (int i = 0; i < n; ++i) *out++ = qd[j * n + i];
    for (int i = 0; i < n; ++i) *out++ = tau[j * n + i];
  }
  for (int j = layout.history; j < layout.num_torques(); ++j)
    for (int i = 0; i < n; ++i) *out++ = tau[j * n + i];
}

void EncodeNominalErrors(const ArmFeatureLayout& layout, ArmNominalStep& nominal, const double* q, const double* qd,
                         const double* tau, double* out) {
  const int n = layout.dof();
  double q_nominal[64], qd_nominal[64];  // dof <= 64 (ArmPredictor::Load)
  std::vector<double> big_q, big_qd;
  double* qn = q_nominal;
  double* qdn = qd_nominal;
  if (n > 64) {
    big_q.resize(static_cast<std::size_t>(n));
    big_qd.resize(big_q.size());
    qn = big_q.data();
    qdn = big_qd.data();
  }
  for (int j = 0; j + 1 < layout.history; ++j) {
    nominal.Step(q + j * n, qd + j * n, tau + j * n, 1, qn, qdn);
    for (int i = 0; i < n; ++i) *out++ = q[(j + 1) * n + i] - qn[i];
    for (int i = 0; i < n; ++i) *out++ = qd[(j + 1) * n + i] - qdn[i];
  }
}

void EncodeArmOutputs(const ArmFeatureLayout& layout, const double* q_i, const double* qd_i, const double* q_later,
                      const double* qd_later, double* out) {
  const int n = layout.dof();
  const double span = layout.horizon * layout.sample_time;
  for (int i = 0; i < n; ++i) out[i] = q_later[i] - q_i[i] - span * qd_i[i];
  for (int i = 0; i < n; ++i) out[n + i] = qd_later[i] - qd_i[i];
}

void DecodeArmOutputs(const ArmFeatureLayout& layout, const double* y, const double* q_i, const double* qd_i,
                      double* q_later, double* qd_later) {
  const int n = layout.dof();
  const double span = layout.horizon * layout.sample_time;
  for (int i = 0; i < n; ++i) {
    q_later[i] = q_i[i] + span * qd_i[i] + y[i];
    qd_later[i] = qd_i[i] + y[n + i];
  }
}

void ArmDataset::Append(const Eigen::MatrixXd& more_x, const Eigen::MatrixXd& more_y) {
  if (x.rows() == 0) {
    x.resize(0, more_x.cols());
    y.resize(0, more_y.cols());
  }
  const long r = x.rows();
  x.conservativeResize(r + more_x.rows(), more_x.cols());
  y.conservativeResize(r + more_y.rows(), more_y.cols());
  x.bottomRows(more_x.rows()) = more_x;
  y.bottomRows(more_y.rows()) = more_y;
}

ArmSequence ToArmSequence(const ArmLog& log, const ArmFeatureLayout& layout) {
  ArmSequence seq;
  const int n = log.dof, rows = log.rows();
  seq.dof = n;
  seq.q.resize(static_cast<std::size_t>(rows * n));
  seq.qd.resize(seq.q.size());
  seq.acting.assign(seq.q.size(), 0.0);
  for (int k = 0; k < rows; ++k) {
    for (int i = 0; i < n; ++i) {
      seq.q[static_cast<std::size_t>(k * n + i)] = log.q(k, i);
      seq.qd[static_cast<std::size_t>(k * n + i)] = log.qd(k, i);
      if (k >= layout.command_lag) seq.acting[static_cast<std::size_t>(k * n + i)] = log.tau(k - layout.command_lag, i);
    }
  }
  seq.first_known_torque = layout.command_lag;
  return seq;
}

int AppendArmSamples(const ArmSequence& seq, const ArmFeatureLayout& layout, int first, int last, ArmDataset* data,
                     ArmNominalStep* nominal) {
  const int n = layout.dof(), h = layout.history, hz = layout.horizon;
  const int begin = std::max(first, seq.first_known_torque + h - 1);
  const int end = std::min(last, seq.rows() - 1 - hz);  // inclusive
  const int count = std::max(0, end - begin + 1);
  if (layout.nominal_errors && !nominal)
    throw std::invalid_argument("AppendArmSamples: the layout's nominal errors need the nominal model's step");
  Eigen::MatrixXd x(count, layout.num_inputs());
  Eigen::MatrixXd y(count, layout.num_outputs());
  Eigen::VectorXd row_x(layout.num_inputs()), row_y(layout.num_outputs()), row_nominal(layout.num_outputs());
  std::vector<double> q_nominal(static_cast<std::size_t>(n)), qd_nominal(q_nominal.size());
  for (int k = 0; k < count; ++k) {
    const int i = begin + k;
    const std::size_t start = static_cast<std::size_t>((i - h + 1) * n);
    EncodeArmInputs(layout, &seq.q[start], &seq.qd[start], &seq.acting[start], row_x.data());
    if (layout.nominal_errors)
      EncodeNominalErrors(layout, *nominal, &seq.q[start], &seq.qd[start], &seq.acting[start],
                          row_x.data() + layout.num_base_inputs());
    const std::size_t now = static_cast<std::size_t>(i * n), later = static_cast<std::size_t>((i + hz) * n);
    EncodeArmOutputs(layout, &seq.q[now], &seq.qd[now], &seq.q[later], &seq.qd[later], row_y.data());
    if (nominal) {
      nominal->Step(&seq.q[now], &seq.qd[now], &seq.acting[now], hz, q_nominal.data(), qd_nominal.data());
      EncodeArmOutputs(layout, &seq.q[now], &seq.qd[now], q_nominal.data(), qd_nominal.data(), row_nominal.data());
      row_y -= row_nominal;
    }
    x.row(k) = row_x.transpose();
    y.row(k) = row_y.transpose();
  }
  if (count > 0) data->Append(x, y);
  return count;
}

}  // namespace twinsim
