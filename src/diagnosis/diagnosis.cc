#include "diagnosis/diagnosis.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <set>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/printf_number.h"
#include "signal/spectrum.h"

namespace twinsim {

bool DiagnosisOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (!(held_out > 0 && held_out < 1)) return fail("--held-out must be between 0 and 1 (exclusive), got " + FormatParameter(held_out));
  if (!(block_seconds >= 0) || !std::isfinite(block_seconds)) return fail("--block must be 0 (automatic) or a positive number of seconds");
  if (max_effects < 0) return fail("--max-effects must be 0 or more, got " + std::to_string(max_effects));
  if (!(min_improvement >= 0 && min_improvement < 1)) return fail("--min-improvement must be in [0, 1)");
  if (!(alpha > 0 && alpha < 1)) return fail("--alpha must be between 0 and 1 (exclusive), got " + FormatParameter(alpha));
  if (horizon < 1) return fail("--horizon must be 1 or more frames, got " + std::to_string(horizon));
  if (!(standstill >= 0) || !std::isfinite(standstill)) return fail("--standstill must be a non-negative speed");
  if (threads < 0) return fail("--threads must be 0 (one per core) or more");
  return true;
}

ReversalWindows::ReversalWindows(const std::vector<double>& t, const std::vector<double>& v, double stand,
                                 double window)
    : window_(window) {
  double vmax = 0;
  for (double x : v) vmax = std::max(vmax, std::abs(x));
  for (std::size_t i = 1; i < v.size() && i < t.size(); ++i) {
    if ((v[i] > 0) != (v[i - 1] > 0) || std::abs(v[i]) < stand * vmax) times_.push_back(t[i]);
  }
}

bool ReversalWindows::Near(double t) {
  while (next_ < times_.size() && times_[next_] < t - window_) ++next_;
  return next_ < times_.size() && times_[next_] <= t + window_;
}

int WelchSegmentFor(std::size_t n, int cap) {
  return static_cast<int>(
      std::min<double>(cap, std::pow(2, std::floor(std::log2(std::max(8.0, static_cast<double>(n) / 4.0))))));
}

void ResidualSpectra(const std::vector<double>& before, const std::vector<double>& after, double rate, int cap,
                     ChannelSeries* s) {
  const int segment = WelchSegmentFor(before.size(), cap);
  WelchPsd(before, rate, segment, &s->frequency, &s->psd_before);
  std::vector<double> unused;
  WelchPsd(after, rate, segment, &unused, &s->psd_after);
}

double Rms(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x * x;
  return v.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(v.size()));
}

void DescribeChannel(const ChannelSamples& x, const ChannelSeries& s, ChannelFinding* f) {
  f->rms = Rms(x.before);
  f->rms_after = Rms(x.after);
  f->rms_near_reversal = Rms(x.near_reversal);
  f->rms_moving = Rms(x.moving);
  f->velocity_correlation = Correlation(x.before, x.velocity);
  f->acceleration_correlation = Correlation(x.before, x.acceleration);
  std::size_t peak = 1;  // above DC
  for (std::size_t b = 1; b < s.psd_before.size(); ++b) {
    if (s.psd_before[b] > s.psd_before[peak]) peak = b;
  }
  f->dominant_frequency = s.frequency.size() > peak ? s.frequency[peak] : 0.0;
}

std::string FormatParameter(double value) { return PrintfNumber("%.4g", value); }

std::string EffectLabel(const std::string& name, int joint) {
  return joint >= 0 ? name + " (joint " + std::to_string(joint + 1) + ")" : name;
}

}  // namespace twinsim
