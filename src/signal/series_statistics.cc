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

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  if (n < 2) return 0;
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= static_cast<double>(n);
  mb /= static_cast<double>(n);
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  if (saa <= 0 || sbb <= 0) return 0;
  return sab / std::sqrt(saa * sbb);
}

Alignment BestAlignment(const std::vector<double>& a, const std::vector<double>& b, int first, int last,
                        bool magnitude) {
  Alignment best;
  bool found = false;
  const long na = static_cast<long>(a.size()), nb = static_cast<long>(b.size());
  const int step = last >= first ? 1 : -1;
  std::vector<double> x, y;
  for (int s = first;; s += step) {
    x.clear();
    y.clear();
    for (long i = std::max(0L, -static_cast<long>(s)); i < std::min(na, nb - s); ++i) {
      x.push_back(a[static_cast<std::size_t>(i)]);
      y.push_back(b[static_cast<std::size_t>(i + s)]);
    }
    const double c = Correlation(x, y);
    const bool better = magnitude ? std::abs(c) > std::abs(best.correlation) : (!found || c > best.correlation);
    if (better) {
      best = {s, c};
      found = true;
    }
    if (s == last) break;
  }
  return best;
}

}  // namespace twinsim
