#include "robots/omni/omni_seen_inputs.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinsim {

double OmniSeenInputs::Distance(const Eigen::VectorXd& u) const {
  if (points.empty() || !(scale > 0)) return 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eigen::VectorXd& p : points) nearest = std::min(nearest, (u - p).squaredNorm());
  return std::sqrt(nearest) / scale;
}

Eigen::VectorXd SeenInputFeature(const Eigen::MatrixXd& wheels_from_body, const Twist2& command,
                                 const Twist2& velocity) {
  const long n = wheels_from_body.rows();
  Eigen::VectorXd u(2 * n);
  u.head(n) = wheels_from_body * Eigen::Vector3d(command.vx, command.vy, command.omega);
  u.tail(n) = wheels_from_body * Eigen::Vector3d(velocity.vx, velocity.vy, velocity.omega);
  return u;
}

OmniSeenInputs MakeSeenInputs(const std::vector<Eigen::VectorXd>& inputs, int most) {
  OmniSeenInputs out;
  if (inputs.empty() || most < 1) return out;
  const long n = inputs.front().size() / 2;
  double sum = 0;
  for (const Eigen::VectorXd& u : inputs) sum += u.head(n).squaredNorm();
  out.scale = std::max(1e-3, std::sqrt(sum / static_cast<double>(inputs.size())));
  // nearest[i]: input i's squared distance from the points taken so far.
  std::vector<double> nearest(inputs.size(), std::numeric_limits<double>::infinity());
  std::size_t next = 0;
  while (static_cast<int>(out.points.size()) < most) {
    out.points.push_back(inputs[next]);
    double farthest = -1;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      nearest[i] = std::min(nearest[i], (inputs[i] - out.points.back()).squaredNorm());
      if (nearest[i] > farthest) farthest = nearest[i], next = i;
    }
    out.covering = std::sqrt(farthest) / out.scale;
    if (farthest <= 0) break;  // every input is a point
  }
  return out;
}

}  // namespace twinsim
