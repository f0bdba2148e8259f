#include "diagnosis/diagnosis.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <set>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/printf_number.h"
#include <unsupported/Eigen/FFT>

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

void WelchPsd(const std::vector<double>& x, double rate, int segment, std::vector<double>* frequency,
              std::vector<double>* psd) {
  frequency->clear();
  psd->clear();
  segment = std::min<int>(segment, static_cast<int>(x.size()));
  segment -= segment % 2;
  if (segment < 8) return;
  std::vector<double> window(static_cast<std::size_t>(segment));
  double window_power = 0;
  for (int i = 0; i < segment; ++i) {
    window[static_cast<std::size_t>(i)] = 0.5 - 0.5 * std::cos(2 * kPi * i / segment);
    window_power += window[static_cast<std::size_t>(i)] * window[static_cast<std::size_t>(i)];
  }
  Eigen::FFT<double> fft;
  std::vector<double> buffer(static_cast<std::size_t>(segment));
  std::vector<std::complex<double>> spectrum;
  const int bins = segment / 2 + 1;
  psd->assign(static_cast<std::size_t>(bins), 0.0);
  int count = 0;
  for (std::size_t start = 0; start + static_cast<std::size_t>(segment) <= x.size(); start += static_cast<std::size_t>(segment / 2)) {
    double mean = 0;
    for (int i = 0; i < segment; ++i) mean += x[start + static_cast<std::size_t>(i)];
    mean /= segment;
    for (int i = 0; i < segment; ++i) {
      buffer[static_cast<std::size_t>(i)] = (x[start + static_cast<std::size_t>(i)] - mean) * window[static_cast<std::size_t>(i)];
    }
    fft.fwd(spectrum, buffer);
    for (int b = 0; b < bins; ++b) {
      const double scale = (b == 0 || b == segment / 2) ? 1.0 : 2.0;
      (*psd)[static_cast<std::size_t>(b)] += scale * std::norm(spectrum[static_cast<std::size_t>(b)]) / (rate * window_power);
    }
    ++count;
  }
  for (double& p : *psd) p /= std::max(count, 1);
  frequency->resize(static_cast<std::size_t>(bins));
  for (int b = 0; b < bins; ++b) (*frequency)[static_cast<std::size_t>(b)] = b * rate / segment;
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
