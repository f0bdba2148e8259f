// Two statistics of a sampled series that the identification and the diagnosis share:
// how many samples its autocorrelation lasts, and a spread that outliers do not move.
#pragma once

#include <vector>

namespace twinsim {

// The first lag (rows) where the autocorrelation of x falls below 1/e, at most max_lag.
int CorrelationLength(const std::vector<double>& x, int max_lag);

// The median absolute deviation scaled to a Gaussian's standard deviation.
double RobustSigma(std::vector<double> x);

}  // namespace twinsim
