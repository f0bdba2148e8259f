#include "analysis/omni_spread_budget.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "estimation/omni_observer.h"

namespace twinsim {

OmniSpreadBudget SpreadBudgetOf(const OmniLog& log, const OmniReplayResult& result, int frames,
                                const std::function<bool(std::size_t)>& keep) {
  OmniSpreadBudget b;
  b.frames = frames;
  b.seconds = frames * log.frame_period;
  if (result.covariance_parts.size() != log.rows.size()) return b;
  double measured = 0, predicted = 0, parameters = 0;
  std::array<double, kCovarianceParts> parts{};
  const bool with_parameters = result.parameter_covariance.size() == log.rows.size();
  const double camera = result.measurement_covariance.topLeftCorner<2, 2>().trace();
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i) || (keep && !keep(i))) continue;
    const Pose2& m = log.rows[i].pose;
    measured += std::pow(m.x - result.pose[i].x, 2) + std::pow(m.y - result.pose[i].y, 2);
    double whole = camera;
    for (int p = 0; p < kCovarianceParts; ++p) {
      const double t = result.covariance_parts[i][static_cast<std::size_t>(p)].topLeftCorner<2, 2>().trace();
      parts[static_cast<std::size_t>(p)] += t;
      whole += t;
    }
    if (with_parameters) {
      const double t = result.parameter_covariance[i].topLeftCorner<2, 2>().trace();
      parameters += t;
      whole += t;
    }
    predicted += whole;
    ++b.rows;
  }
  if (b.rows == 0) return b;
  const double n = b.rows;
  b.measured = std::sqrt(measured / n);
  b.predicted = std::sqrt(predicted / n);
  for (int p = 0; p < kCovarianceParts; ++p) b.parts[static_cast<std::size_t>(p)] = std::sqrt(parts[static_cast<std::size_t>(p)] / n);
  b.camera = std::sqrt(camera);
  b.parameters = std::sqrt(parameters / n);
  return b;
}

std::vector<OmniSpreadBudget> PoolSpreadBudgets(const std::vector<std::vector<OmniSpreadBudget>>& per_log) {
  std::vector<OmniSpreadBudget> out;
  for (const auto& budgets : per_log) {
    if (out.empty()) {
      out.resize(budgets.size());
      for (std::size_t q = 0; q < budgets.size(); ++q) {
        out[q].frames = budgets[q].frames, out[q].seconds = budgets[q].seconds, out[q].scale = budgets[q].scale;
      }
    }
    for (std::size_t q = 0; q < budgets.size() && q < out.size(); ++q) {
      const OmniSpreadBudget& b = budgets[q];
      OmniSpreadBudget& o = out[q];
      auto add = [&](double* sum, double v) { *sum += b.rows * v * v; };
      add(&o.measured, b.measured);
      add(&o.predicted, b.predicted);
      for (std::size_t p = 0; p < o.parts.size(); ++p) add(&o.parts[p], b.parts[p]);
      add(&o.camera, b.camera);
      add(&o.parameters, b.parameters);
      o.rows += b.rows;
    }
  }
  for (OmniSpreadBudget& o : out) {
    const double n = std::max(1, o.rows);
    o.measured = std::sqrt(o.measured / n), o.predicted = std::sqrt(o.predicted / n), o.camera = std::sqrt(o.camera / n);
    o.parameters = std::sqrt(o.parameters / n);
    for (double& p : o.parts) p = std::sqrt(p / n);
  }
  return out;
}

std::string FormatSpreadBudgets(const std::vector<OmniSpreadBudget>& budgets) {
  std::ostringstream s;
  char line[320];
  bool parameters = false;  // a column where any horizon has the parameters' part
  for (const OmniSpreadBudget& b : budgets) parameters = parameters || b.parameters > 0;
  std::snprintf(line, sizeof line, "  %-20s %6s %9s %10s %9s   %-14s %-13s %-13s %-9s %-7s%s\n", "horizon", "rows",
                "measured", "predicted", "ratio", "start estimate", "process noise", "driving noise", "drift", "camera",
                parameters ? " parameters" : "");
  s << line;
  for (const OmniSpreadBudget& b : budgets) {
    if (b.rows == 0) continue;
    char label[48];
    std::snprintf(label, sizeof label, "%d frames (%.2f s)", b.frames, b.seconds);
    // The safeguard scales the filter's covariance, not the camera's or the parameters'.
    const double fixed = b.camera * b.camera + b.parameters * b.parameters;
    const double spread = std::sqrt(b.scale * b.scale * (b.predicted * b.predicted - fixed) + fixed);
    char more[32] = "";
    if (parameters) std::snprintf(more, sizeof more, " %-10.2f", 1000 * b.parameters);
    std::snprintf(line, sizeof line, "  %-20s %6d %9.2f %10.2f %9.2f   %-14.2f %-13.2f %-13.2f %-9.2f %-7.2f%s\n", label,
                  b.rows, 1000 * b.measured, 1000 * spread, b.measured / spread, 1000 * b.parts[kStartEstimate],
                  1000 * b.parts[kProcessNoise], 1000 * b.parts[kDrivingNoise], 1000 * b.parts[kDrift], 1000 * b.camera,
                  more);
    s << line;
  }
  return s.str();
}

}  // namespace twinsim
