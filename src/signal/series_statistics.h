// Statistics of sampled series that the identification and the diagnosis share: how
// many samples an autocorrelation lasts, a spread that outliers do not move, the
// correlation of two series, and the one lag estimator (BestAlignment) every lag the
// diagnosis reads is taken with.
#pragma once

#include <vector>

namespace twinsim {

// The first lag (rows) where the autocorrelation of x falls below 1/e, at most max_lag.
int CorrelationLength(const std::vector<double>& x, int max_lag);

// The median absolute deviation scaled to a Gaussian's standard deviation.
double RobustSigma(std::vector<double> x);

// Pearson correlation of a and b over their common length (0 when either is constant or
// shorter than 2).
double Correlation(const std::vector<double>& a, const std::vector<double>& b);

// Where two series line up best: the shift s (samples) at which the correlation of a[i]
// with b[i + s], over the i both hold, is largest (in magnitude with `magnitude`), s
// scanned from `first` to `last` (either way round) and a tie kept at the shift met
// first. Without `magnitude` some shift is always found; with it, none beats a
// correlation of 0 and then the shift is 0.
struct Alignment {
  int shift = 0;
  double correlation = 0;
};
Alignment BestAlignment(const std::vector<double>& a, const std::vector<double>& b, int first, int last,
                        bool magnitude = false);

}  // namespace twinsim
