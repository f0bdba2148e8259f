#include "learning/omni_features.h"

#include <cmath>
#include <map>

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
    *out++ = std::cos(dtheta);
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

Eigen::Vector3d EncodeDelta(const Pose2& now, const Pose2& later) {
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  const double dx = later.x - now.x, dy = later.y - now.y;
  return Eigen::Vector3d(c * dx + s * dy, -s * dx + c * dy, WrapAngle(later.theta - now.theta));
}

Pose2 ApplyDelta(const Pose2& now, const Eigen::Vector3d& delta) {
  const double c = std::cos(now.theta), s = std::sin(now.theta);
  return Pose2{now.x + c * delta[0] - s * delta[1], now.y + s * delta[0] + c * delta[1], now.theta + delta[2]};
}

int AppendSamples(const OmniLog& log, const FeatureLayout& layout, OmniDataset* data) {
  const std::size_t n = log.rows.size();
  std::map<int, std::size_t> row_of_frame;
  for (std::size_t i = 0; i < n; ++i) row_of_frame[log.FrameIndex(i)] = i;
  const int last = log.FrameIndex(n - 1);
  // The command logged at each frame, held over lost frames.
  std::vector<Twist2> logged(static_cast<std::size_t>(last) + 1);
  for (int f = 0, row = 0; f <= last; ++f) {
    while (static_cast<std::size_t>(row + 1) < n && log.FrameIndex(static_cast<std::size_t>(row + 1)) <= f) ++row;
    logged[static_cast<std::size_t>(f)] = log.rows[static_cast<std::size_t>(row)].command;
  }

  std::vector<Pose2> poses(static_cast<std::size_t>(layout.history));
  std::vector<Twist2> commands(static_cast<std::size_t>(layout.num_commands()));
  std::vector<Eigen::VectorXd> xs;
  std::vector<Eigen::Vector3d> ys;
  for (int i = layout.history - 1; i + layout.horizon <= last; ++i) {
    const int first = i - layout.history + 1;
    if (first - layout.command_lag < 0) continue;
    bool complete = row_of_frame.count(i + layout.horizon) > 0;
    for (int j = 0; j < layout.history && complete; ++j) {
      auto it = row_of_frame.find(first + j);
      if (it == row_of_frame.end()) complete = false;
      else poses[static_cast<std::size_t>(j)] = log.rows[it->second].pose;
    }
    if (!complete) continue;
    for (int j = 0; j < layout.num_commands(); ++j)
      commands[static_cast<std::size_t>(j)] = logged[static_cast<std::size_t>(first + j - layout.command_lag)];
    Eigen::VectorXd x(layout.num_inputs());
    EncodeInputs(layout, poses.data(), commands.data(), x.data());
    xs.push_back(std::move(x));
    ys.push_back(EncodeDelta(poses.back(), log.rows[row_of_frame[i + layout.horizon]].pose));
  }
  const int old_rows = data->rows();
  const int added = static_cast<int>(xs.size());
  if (old_rows == 0) {
    data->x.resize(0, layout.num_inputs());
    data->y.resize(0, FeatureLayout::kNumOutputs);
  }
  data->x.conservativeResize(old_rows + added, layout.num_inputs());
  data->y.conservativeResize(old_rows + added, FeatureLayout::kNumOutputs);
  for (int k = 0; k < added; ++k) {
    data->x.row(old_rows + k) = xs[static_cast<std::size_t>(k)].transpose();
    data->y.row(old_rows + k) = ys[static_cast<std::size_t>(k)].transpose();
  }
  return added;
}

}  // namespace twinsim
