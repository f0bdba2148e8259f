#include "learning/omni_features.h"

#include <cmath>
#include <algorithm>

namespace twinsim {

void EncodeInputs(const FeatureLayout& layout, const Pose2* poses, const Twist2* commands, double* out) {
  const Pose2& now = poses[layout.history - 1];
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  for (int j = 0; j < layout.history; ++j) {
    const double dx = poses[j].x - now.x, dy = poses[j].y - now.y;
    const double dtheta = poses[j].theta - now.theta;
    *out++ = c * dx + s * dy;
    *out++ = -s * dx + c * dy;
    *out++ = std::sin(dtheta);
    *out++ = std::cos(dtheta) - 1;  // so that a robot at rest has all-zero inputs
    *out++ = commands[j].vx;
    *out++ = commands[j].vy;
    *out++ = commands[j].omega;
  }
  for (int j = layout.history; j < layout.num_commands(); ++j) {
    *out++ = commands[j].vx;
    *out++ = commands[j].vy;
    *out++ = commands[j].omega;
  }
}

Eigen::Vector3d EncodeResidualInputs(const FeatureLayout& layout, const Pose2* poses, const Twist2* commands,
                                     const Pose2& nominal_end, const Twist2& nominal_velocity,
                                     const std::vector<Eigen::Vector3d>& errors, double* out) {
  EncodeInputs(layout, poses, commands, out);
  out += layout.num_seed_inputs();
  const Pose2& now = poses[layout.history - 1];
  const Eigen::Vector3d nominal = EncodeDelta(now, nominal_end);
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  *out++ = nominal[0];
  *out++ = nominal[1];
  *out++ = nominal[2];
  *out++ = nominal_velocity.vx;
  *out++ = nominal_velocity.vy;
  *out++ = nominal_velocity.omega;
  for (std::size_t j = errors.size() - static_cast<std::size_t>(layout.nominal_errors); j < errors.size(); ++j) {
    const Eigen::Vector3d& e = errors[j];
    *out++ = c * e[0] + s * e[1];
    *out++ = -s * e[0] + c * e[1];
    *out++ = e[2];
  }
  return nominal;
}

Eigen::Vector3d EncodeDelta(const Pose2& now, const Pose2& later) {
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  const double dx = later.x - now.x, dy = later.y - now.y;
  return Eigen::Vector3d(c * dx + s * dy, -s * dx + c * dy, WrapAngle(later.theta - now.theta));
}

Pose2 ApplyDelta(const Pose2& now, const Eigen::Vector3d& delta) {
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  return Pose2{now.x + c * delta[0] - s * delta[1], now.y + s * delta[0] + c * delta[1], now.theta + delta[2]};
}

bool FrameSequence::Complete(int from, int to) const {
  if (from < 0 || to >= frames()) return false;
  for (int f = from; f <= to; ++f)
    if (!observed[static_cast<std::size_t>(f)]) return false;
  return true;
}

bool FrameSequence::Sampled(int from, int to) const {
  if (sampled.empty()) return true;
  for (int f = std::max(from, 0); f <= to && f < frames(); ++f)
    if (!sampled[static_cast<std::size_t>(f)]) return false;
  return true;
}

bool FrameSequence::Usable(int from, int to) const {
  if (from < 0 || to >= frames() || !observed[static_cast<std::size_t>(from)] || !observed[static_cast<std::size_t>(to)]) {
    return false;
  }
  int lost = 0;
  for (int f = from + 1; f < to; ++f) lost += !observed[static_cast<std::size_t>(f)];
  return lost <= kMaxLostInWindow;
}

FrameSequence ToFrameSequence(const OmniLog& log, const FeatureLayout& layout) {
  const std::size_t n = log.rows.size();
  const int frames = log.FrameIndex(n - 1) + 1;
  FrameSequence seq;
  seq.pose.resize(static_cast<std::size_t>(frames));
  seq.observed.assign(static_cast<std::size_t>(frames), false);
  seq.acting.resize(static_cast<std::size_t>(frames));
  seq.first_known_command = layout.command_lag;
  std::vector<Twist2> logged(static_cast<std::size_t>(frames));
  for (int f = 0, row = 0; f < frames; ++f) {
    // The command logged at each frame, held over lost frames.
    while (static_cast<std::size_t>(row + 1) < n && log.FrameIndex(static_cast<std::size_t>(row + 1)) <= f) ++row;
    logged[static_cast<std::size_t>(f)] = log.rows[static_cast<std::size_t>(row)].command;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<std::size_t>(log.FrameIndex(i));
    seq.pose[f] = log.rows[i].pose;
    seq.observed[f] = log.rows[i].measured;  // a frame without a new pose is a lost one
  }
  // Lost frames: interpolated in time between the measured frames around them (heading
  // on its unwrapped branch), held after the last one.
  int before = -1;
  for (int f = 0; f < frames; ++f) {
    const auto uf = static_cast<std::size_t>(f);
    if (seq.observed[uf]) {
      before = f;
      continue;
    }
    int after = f + 1;
    while (after < frames && !seq.observed[static_cast<std::size_t>(after)]) ++after;
    if (before < 0) continue;  // before the first measurement: as logged
    const Pose2& a = seq.pose[static_cast<std::size_t>(before)];
    if (after >= frames) {
      seq.pose[uf] = a;
      continue;
    }
    const Pose2& b = seq.pose[static_cast<std::size_t>(after)];
    const double w = static_cast<double>(f - before) / static_cast<double>(after - before);
    seq.pose[uf] = Pose2{a.x + w * (b.x - a.x), a.y + w * (b.y - a.y), a.theta + w * (b.theta - a.theta)};
  }
  for (int f = layout.command_lag; f < frames; ++f)
    seq.acting[static_cast<std::size_t>(f)] = logged[static_cast<std::size_t>(f - layout.command_lag)];
  return seq;
}

void AppendRows(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, OmniDataset* data) {
  if (data->x.cols() == 0 && data->x.rows() == 0) {
    data->x.resize(0, x.cols());
    data->y.resize(0, y.cols());
  }
  const long r = data->x.rows();
  data->x.conservativeResize(r + x.rows(), x.cols());
  data->y.conservativeResize(r + y.rows(), y.cols());
  data->x.bottomRows(x.rows()) = x;
  data->y.bottomRows(y.rows()) = y;
}

int AppendSamples(const FrameSequence& seq, const FeatureLayout& layout, int first, int last, OmniDataset* data) {
  std::vector<int> ends;
  for (int i = std::max(first, layout.history - 1); i <= last && i + layout.horizon < seq.frames(); ++i) {
    const int start = i - layout.history + 1;
    if (start < seq.first_known_command) continue;
    if (!seq.Usable(start, i) || !seq.observed[static_cast<std::size_t>(i + layout.horizon)] ||
        !seq.Sampled(start, i + layout.horizon)) {
      continue;
    }
    ends.push_back(i);
  }
  Eigen::MatrixXd x(static_cast<long>(ends.size()), layout.num_inputs());
  Eigen::MatrixXd y(static_cast<long>(ends.size()), FeatureLayout::kNumOutputs);
  for (std::size_t k = 0; k < ends.size(); ++k) {
    const int start = ends[k] - layout.history + 1;
    Eigen::VectorXd row(layout.num_inputs());
    EncodeInputs(layout, &seq.pose[static_cast<std::size_t>(start)], &seq.acting[static_cast<std::size_t>(start)],
                 row.data());
    x.row(static_cast<long>(k)) = row.transpose();
    y.row(static_cast<long>(k)) = EncodeDelta(seq.pose[static_cast<std::size_t>(ends[k])],
                                              seq.pose[static_cast<std::size_t>(ends[k] + layout.horizon)])
                                      .transpose();
  }
  AppendRows(x, y, data);
  return static_cast<int>(ends.size());
}

int AppendSamples(const OmniLog& log, const FeatureLayout& layout, OmniDataset* data) {
  const FrameSequence seq = ToFrameSequence(log, layout);
  return AppendSamples(seq, layout, 0, seq.frames() - 1, data);
}

}  // namespace twinsim
