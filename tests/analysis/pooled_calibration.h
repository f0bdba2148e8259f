// Calibration judged on many unseen minutes at once (issue 42's tests): one minute of a
// wandering robot holds only some 260 independent stretches of its wander, so the share
// of it inside an interval wanders by 1-2 % at 4 frames and 3-5 % at 63 from minute to
// minute. The tests pool the rows of several minutes and say how much the minutes differ.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "io/printf_number.h"
#include "robots/omni/omni_model.h"

namespace twinsim::testing {

// Per horizon: the shares and scores over all rows of all minutes, and the spread of the
// minutes' own shares.
struct PooledCalibration {
  OmniCalibration pooled;  // counts and means over every row of every minute
  int minutes = 0;
  double position_50_sd = 0, position_90_sd = 0;  // across the minutes' own shares
};

// `per_minute[m][h]`: minute m's calibration at horizon h (the same horizons for every
// minute).
inline std::vector<PooledCalibration> PoolCalibrations(const std::vector<std::vector<OmniCalibration>>& per_minute) {
  std::vector<PooledCalibration> out;
  if (per_minute.empty()) return out;
  for (std::size_t h = 0; h < per_minute.front().size(); ++h) {
    PooledCalibration p;
    OmniCalibration& c = p.pooled;
    c.frames = per_minute.front()[h].frames;
    c.seconds = per_minute.front()[h].seconds;
    double s50 = 0, s90 = 0, q50 = 0, q90 = 0;
    for (const std::vector<OmniCalibration>& minute : per_minute) {
      const OmniCalibration& m = minute[h];
      const double n = m.rows;
      c.rows += m.rows;
      c.position_50 += n * m.position_50, c.position_90 += n * m.position_90;
      c.heading_50 += n * m.heading_50, c.heading_90 += n * m.heading_90;
      c.energy_score += n * m.energy_score, c.baseline_energy_score += n * m.baseline_energy_score;
      c.log_score += n * m.log_score;
      s50 += m.position_50, s90 += m.position_90;
      q50 += m.position_50 * m.position_50, q90 += m.position_90 * m.position_90;
      ++p.minutes;
    }
    if (c.rows > 0) {
      const double n = c.rows;
      c.position_50 /= n, c.position_90 /= n, c.heading_50 /= n, c.heading_90 /= n;
      c.energy_score /= n, c.baseline_energy_score /= n, c.log_score /= n;
    }
    const double k = p.minutes;
    p.position_50_sd = std::sqrt(std::max(0.0, q50 / k - (s50 / k) * (s50 / k)));
    p.position_90_sd = std::sqrt(std::max(0.0, q90 / k - (s90 / k) * (s90 / k)));
    out.push_back(p);
  }
  return out;
}

// A JSON list of [frames, seconds, rows, p50, p90, h50, h90, energy, baseline, p50_sd,
// p90_sd] per horizon, for the scripts that print docs' tables.
inline std::string PooledCalibrationJson(const std::vector<PooledCalibration>& pooled) {
  std::string out = "[";
  for (const PooledCalibration& p : pooled) {
    const OmniCalibration& c = p.pooled;
    out += (&p == &pooled.front() ? "[" : ", [") + std::to_string(c.frames) + ", " + PrintfNumber("%.6g", c.seconds) + ", " +
           std::to_string(c.rows);
    for (double v : {c.position_50, c.position_90, c.heading_50, c.heading_90, c.energy_score, c.baseline_energy_score,
                     p.position_50_sd, p.position_90_sd})
      out += ", " + PrintfNumber("%.6g", v);
    out += "]";
  }
  return out + "]";
}

// The row scripts/noise-calibration-table prints a table from: the fitted `noise`
// (spreads, correlation time, growths), the plant's `truth` where known ({} otherwise:
// spreads and correlation time), how many minutes were pooled, and PooledCalibrationJson.
inline std::string NoiseTableRow(const OmniDrivingNoise& noise, const std::vector<double>& truth, int minutes,
                                 const std::vector<PooledCalibration>& pooled) {
  auto list = [](const std::vector<double>& v) {
    std::string out = "[";
    for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + PrintfNumber("%.6g", v[i]);
    return out + "]";
  };
  std::string row = "{\"noise\": " + list({noise.sd[0], noise.sd[1], noise.sd[2], noise.correlation_time, noise.per_speed,
                                            noise.per_acceleration, noise.per_turn_rate});
  if (!truth.empty()) row += ", \"truth\": " + list(truth);
  return row + ", \"minutes\": " + std::to_string(minutes) + ", \"horizons\": " + PooledCalibrationJson(pooled) + "}";
}

}  // namespace twinsim::testing
