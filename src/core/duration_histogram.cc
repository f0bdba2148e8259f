#include "core/duration_histogram.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace twinsim {

DurationHistogram::DurationHistogram(double bin_width, int bins) : bin_width_(bin_width) {
  if (!(bin_width > 0) || bins <= 0) throw std::invalid_argument("DurationHistogram: bin width and count must be positive");
  counts_.assign(static_cast<std::size_t>(bins), 0);
}

void DurationHistogram::Add(double seconds) {
  seconds = std::max(0.0, seconds);
  ++count_;
  sum_ += seconds;
  max_ = std::max(max_, seconds);
  const double bin = std::floor(seconds / bin_width_);
  if (bin >= static_cast<double>(counts_.size())) {
    ++overflow_;
  } else {
    ++counts_[static_cast<std::size_t>(bin)];
  }
}

double DurationHistogram::mean() const { return count_ == 0 ? 0 : sum_ / static_cast<double>(count_); }

long long DurationHistogram::CountBetween(double from, double to) const {
  const long long n = static_cast<long long>(counts_.size());
  const long long first = std::clamp(std::llround(from / bin_width_), 0LL, n);
  const double last_edge = std::round(to / bin_width_);
  const long long last = last_edge >= static_cast<double>(n) ? n : std::max(0LL, std::llround(last_edge));
  long long total = 0;
  for (long long b = first; b < last; ++b) total += counts_[static_cast<std::size_t>(b)];
  if (last_edge >= static_cast<double>(n) && first <= n) total += overflow_;
  return total;
}

double DurationHistogram::Quantile(double q) const {
  if (count_ == 0) return 0;
  const auto rank = std::max(1LL, static_cast<long long>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_))));
  long long seen = 0;
  for (std::size_t b = 0; b < counts_.size(); ++b) {
    seen += counts_[b];
    if (seen >= rank) return std::min(max_, static_cast<double>(b + 1) * bin_width_);
  }
  return max_;
}

std::string DurationHistogram::Brief() const {
  return "n " + std::to_string(count_) + ", mean " + FormatDuration(mean()) + ", p50 " + FormatDuration(Quantile(0.5)) +
         ", p99 " + FormatDuration(Quantile(0.99)) + ", max " + FormatDuration(max_);
}

std::string FormatDuration(double seconds) {
  char text[32];
  const double a = std::abs(seconds);
  if (a >= 1) {
    std::snprintf(text, sizeof text, "%.3g s", seconds);
  } else if (a >= 1e-3) {
    std::snprintf(text, sizeof text, "%.3g ms", 1e3 * seconds);
  } else {
    std::snprintf(text, sizeof text, "%.3g µs", 1e6 * seconds);
  }
  return text;
}

}  // namespace twinsim
