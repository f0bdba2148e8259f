// A histogram of durations in bins of one width, for timing a loop while it runs: the
// bins are allocated once, at construction, and Add is a few arithmetic operations with
// no allocation, so it can sit inside a real-time loop. Durations beyond the last bin
// are counted in an overflow bin; the exact maximum is kept. Quantiles are the upper
// edge of the bin that holds them (exact to one bin width), the maximum for the top one.
//
//   DurationHistogram work(50e-6, 1000);       // 50 µs bins up to 50 ms
//   work.Add(Seconds(end - start));
//   std::printf("p99 %.2f ms\n", 1e3 * work.Quantile(0.99));
#pragma once

#include <string>
#include <vector>

namespace twinsim {

class DurationHistogram {
 public:
  DurationHistogram() = default;
  // `bins` bins of `bin_width` s each from 0. Throws std::invalid_argument when either is
  // not positive.
  DurationHistogram(double bin_width, int bins);

  // Counts one duration (s); a negative one counts as 0.
  void Add(double seconds);

  double bin_width() const { return bin_width_; }  // s
  int bins() const { return static_cast<int>(counts_.size()); }
  long long count() const { return count_; }        // every duration added
  long long count(int bin) const { return counts_[static_cast<std::size_t>(bin)]; }
  long long overflow() const { return overflow_; }  // durations from bins() * bin_width() on
  double max() const { return max_; }               // s; 0 when empty
  double mean() const;                              // s; 0 when empty

  // The durations in [from, to) s, both rounded to the nearest bin edge; `to` beyond
  // the last bin takes in the overflow.
  long long CountBetween(double from, double to) const;
  // The q-quantile (0 < q <= 1), s: the upper edge of the bin that holds the
  // ceil(q * count())-th smallest duration, no more than max(); 0 when empty.
  double Quantile(double q) const;
  // "n 1200, mean 0.91 ms, p50 0.90 ms, p99 1.25 ms, max 1.43 ms" (µs below 1 ms).
  std::string Brief() const;

 private:
  double bin_width_ = 1;  // s
  std::vector<long long> counts_;
  long long overflow_ = 0;
  long long count_ = 0;
  double sum_ = 0;  // s
  double max_ = 0;  // s
};

// "0.91 ms", "37 µs", "1.2 s": a duration in the unit that reads best.
std::string FormatDuration(double seconds);

}  // namespace twinsim
