#include "render/plot_style.h"

#include <cmath>
#include <cstdio>

namespace twinsim::plot_style {

std::string FormatTick(double v, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  const double rounded = std::round(v / step) * step;
  if (std::abs(rounded) < step * 1e-6) return "0";
  char buf[64];
  if (std::abs(rounded) >= 1e7 || decimals > 6)
    std::snprintf(buf, sizeof buf, "%g", std::abs(rounded));
  else
    std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(rounded));
  return (rounded < 0 ? "\u2212" : "") + std::string(buf);
}

std::vector<double> Ticks(double lo, double hi, double step) {
  std::vector<double> out;
  const double eps = step * 1e-6;
  for (long long k = static_cast<long long>(std::ceil((lo - eps) / step)); k * step <= hi + eps; ++k) {
    out.push_back(k * step);
    if (out.size() > 1000) break;
  }
  return out;
}

}  // namespace twinsim::plot_style
