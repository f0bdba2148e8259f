#include "signal/series_statistics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace twinsim {

int CorrelationLength(const std::vector<double>& x, int max_lag) {
  const std::size_t n = x.size();
  if (n < 4) return 1;
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  if (c0 <= 0) return 1;
  for (int lag = 1; lag <= max_lag && static_cast<std::size_t>(lag) < n; ++lag) {
    double c = 0;
    for (std::size_t i = static_cast<std::size_t>(lag); i < n; ++i) c += (x[i] - mean) * (x[i - static_cast<std::size_t>(lag)] - mean);
    if (c / c0 < std::exp(-1.0)) return lag;
  }
  return max_lag;
}

double RobustSigma(std::vector<double> x) {
  if (x.empty()) return 0;
  auto median = [](std::vector<double>& v) {
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
    return v[mid];
  };
  const double m = median(x);
  for (double& v : x) v = std::abs(v - m);
  return 1.4826 * median(x);
}

}  // namespace twinsim
