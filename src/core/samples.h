// Spans of time as counts of samples, for lengths a user gives in seconds (a simulation
// window, a shooting segment): rounded, and capped so that a span longer than any log
// (a window of 1e300 s) stays a long span instead of wrapping round an int.
//
//   const int length = std::max(1, SamplesIn(window_seconds, log.sample_period));
#pragma once

#include <cmath>

namespace twinsim {

// Far longer than any log (6 days at 1 kHz), and small enough that a few of them added
// to a row index still fit in an int.
inline constexpr int kMostSamples = 1 << 29;

// round(seconds / period), at most kMostSamples (and 0 for a span that is not positive).
inline int SamplesIn(double seconds, double period) {
  const double n = std::round(seconds / period);
  if (!(n > 0)) return 0;
  return n >= kMostSamples ? kMostSamples : static_cast<int>(n);
}

}  // namespace twinsim
