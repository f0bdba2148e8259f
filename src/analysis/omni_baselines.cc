#include "analysis/omni_baselines.h"

#include <cstddef>
#include <vector>

#include "core/pose.h"

namespace twinsim {
namespace {

// The rows with a measurement, and for each row i the index into them of the last one
// at or before frame(i) - horizon (-1: none).
struct MeasuredBefore {
  std::vector<std::size_t> measured;
  std::vector<long> last;  // per row
};

MeasuredBefore FindMeasuredBefore(const OmniLog& log, int horizon) {
  MeasuredBefore out;
  const std::size_t n = log.rows.size();
  for (std::size_t i = 0; i < n; ++i)
    if (log.rows[i].measured) out.measured.push_back(i);
  out.last.assign(n, -1);
  std::size_t m = 0;  // measured[m] is the first measured row after the start frame
  for (std::size_t i = 0; i < n; ++i) {
    const int start = log.FrameIndex(i) - horizon;
    if (start < 0) continue;
    while (m < out.measured.size() && log.FrameIndex(out.measured[m]) <= start) ++m;
    out.last[i] = static_cast<long>(m) - 1;
  }
  return out;
}

}  // namespace

OmniReplayResult ConstantVelocityPrediction(const OmniLog& log, int horizon) {
  OmniReplayResult out = HeldMeasurements(log);
  out.state = "constant velocity";
  const MeasuredBefore before = FindMeasuredBefore(log, horizon);
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const long m = before.last[i];
    if (m < 1) continue;
    const OmniLogRow& b = log.rows[before.measured[static_cast<std::size_t>(m)]];
    const OmniLogRow& a = log.rows[before.measured[static_cast<std::size_t>(m - 1)]];
    const double dt = b.t - a.t, ahead = log.rows[i].t - b.t;
    out.pose[i] = Pose2{b.pose.x + (b.pose.x - a.pose.x) / dt * ahead, b.pose.y + (b.pose.y - a.pose.y) / dt * ahead,
                        b.pose.theta + (b.pose.theta - a.pose.theta) / dt * ahead};
    out.predicted[i] = true;
  }
  return out;
}

OmniReplayResult IntegratedCommandPrediction(const OmniLog& log, int horizon, double delay) {
  OmniReplayResult out = HeldMeasurements(log);
  out.state = "integrated command";
  const MeasuredBefore before = FindMeasuredBefore(log, horizon);
  const std::size_t n = log.rows.size();
  // command_row[j]: the row whose command acts at row j's time (sent `delay` earlier);
  // -1 before the first command.
  std::vector<long> command_row(n, -1);
  long c = -1;
  for (std::size_t j = 0; j < n; ++j) {
    while (c + 1 < static_cast<long>(n) && log.rows[static_cast<std::size_t>(c + 1)].t <= log.rows[j].t - delay + 1e-9) ++c;
    command_row[j] = c;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const long m = before.last[i];
    if (m < 0) continue;
    const std::size_t from = before.measured[static_cast<std::size_t>(m)];
    if (command_row[from] < 0) continue;
    Pose2 p = log.rows[from].pose;
    // Each row interval at the command acting at its start (zero-order hold).
    for (std::size_t j = from; j < i; ++j) {
      const Twist2 v = BodyToField(log.rows[static_cast<std::size_t>(command_row[j])].command, p.theta);
      const double dt = log.rows[j + 1].t - log.rows[j].t;
      p.x += v.vx * dt;
      p.y += v.vy * dt;
      p.theta += v.omega * dt;
    }
    out.pose[i] = p;
    out.predicted[i] = true;
  }
  return out;
}

}  // namespace twinsim
