#include "render/plot_style.h"

#include <cmath>
#include <cstdio>

#include "core/pose.h"
#include "render/plot.h"

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

void DrawStartEndMarkers(Renderer& r, const std::vector<std::optional<Point2d>>& starts,
                         const std::vector<std::optional<Point2d>>& ends) {
  const int n = static_cast<int>(starts.size());
  auto radius = [&](const std::vector<std::optional<Point2d>>& at, int k) {
    int covered_by = 0;
    for (int j = k + 1; j < n; ++j)
      covered_by += at[j] && std::hypot(at[j]->x - at[k]->x, at[j]->y - at[k]->y) < kMarkerRadius;
    return kMarkerRadius + kMarkerStep * covered_by;
  };
  for (int k = 0; k < n; ++k) {
    if (!starts[k]) continue;
    const Point2d s = *starts[k], e = *ends[k];
    const double rs = radius(starts, k);
    r.FillCircle(s, rs + kMarkerRing, kWhite);
    r.FillCircle(s, rs, PlotColor(k));
    const double h = radius(ends, k) * std::sqrt(kPi) / 2;  // the square's half side: same area as a circle
    r.FillRect(Rect{e.x - h - kMarkerRing, e.y - h - kMarkerRing, e.x + h + kMarkerRing, e.y + h + kMarkerRing}, kWhite);
    r.FillRect(Rect{e.x - h, e.y - h, e.x + h, e.y + h}, PlotColor(k));
  }
}

}  // namespace twinsim::plot_style
