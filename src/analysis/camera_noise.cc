#include "analysis/camera_noise.h"

#include <cmath>

#include "signal/series_statistics.h"

namespace twinsim {

double OmniNoiseFloor(const std::vector<OmniLog>& logs, double radius, double* var_xy_out, double* var_theta_out) {
  double var_xy = 0, var_theta = 0;
  for (const OmniLog& log : logs) {
    // Camera noise from third differences (a smooth path's are tiny): var = E[d3^2] / 20,
    // over four consecutive frames that each hold a new measurement (a repeated or
    // missing pose is not the camera's noise).
    std::vector<double> d3x, d3y, d3t;
    for (std::size_t i = 3; i < log.rows.size(); ++i) {
      if (log.FrameIndex(i) - log.FrameIndex(i - 3) != 3) continue;
      if (!(log.rows[i].measured && log.rows[i - 1].measured && log.rows[i - 2].measured && log.rows[i - 3].measured))
        continue;
      auto third = [&](auto get) {
        return get(log.rows[i]) - 3 * get(log.rows[i - 1]) + 3 * get(log.rows[i - 2]) - get(log.rows[i - 3]);
      };
      d3x.push_back(third([](const OmniLogRow& r) { return r.pose.x; }));
      d3y.push_back(third([](const OmniLogRow& r) { return r.pose.y; }));
      d3t.push_back(third([](const OmniLogRow& r) { return r.pose.theta; }));
    }
    const double sx = RobustSigma(d3x), sy = RobustSigma(d3y), st = RobustSigma(d3t);
    var_xy += (sx * sx + sy * sy) / 2 / 20;
    var_theta += st * st / 20;
  }
  var_xy /= static_cast<double>(logs.size());
  var_theta /= static_cast<double>(logs.size());
  if (var_xy_out) *var_xy_out = var_xy;
  if (var_theta_out) *var_theta_out = var_theta;
  // Start and end poses both carry the camera's noise.
  return std::sqrt(4 * var_xy + 2 * radius * radius * var_theta);
}

}  // namespace twinsim
