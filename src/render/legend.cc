#include "render/legend.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/math_constants.h"
#include "render/plot_style.h"

namespace twinsim::plot_style {
namespace {

// The start/end key's row: circle, "start", square, "end"; x offsets from the row's left.
struct MarkerKeyRow {
  double circle, start_text, square, end_text, width;
};

MarkerKeyRow MarkerKey() {
  const double h = kMarkerRadius * std::sqrt(kPi) / 2;  // the square's half side: same area as the circle
  MarkerKeyRow k;
  k.circle = kMarkerRadius + 2;
  k.start_text = k.circle + kMarkerRadius + 6;
  k.square = k.start_text + MeasureText("start", {}, LegendStyle()).width() + 18 + h;
  k.end_text = k.square + h + 6;
  k.width = k.end_text + MeasureText("end", {}, LegendStyle()).width();
  return k;
}

}  // namespace

Occupancy::Occupancy(const Rect& area) : area_(area) {
  nx_ = std::max(1, static_cast<int>(std::ceil(area.width() / kCell)));
  ny_ = std::max(1, static_cast<int>(std::ceil(area.height() / kCell)));
  cells_.assign(static_cast<std::size_t>(nx_) * ny_, 0);
}

void Occupancy::MarkRect(const Rect& r) {
  for (int j = std::max(Cell(r.y0 - area_.y0), 0); j <= std::min(Cell(r.y1 - area_.y0), ny_ - 1); ++j)
    for (int i = std::max(Cell(r.x0 - area_.x0), 0); i <= std::min(Cell(r.x1 - area_.x0), nx_ - 1); ++i)
      cells_[static_cast<std::size_t>(j) * nx_ + i] = 1;
}

void Occupancy::MarkDisc(Point2d p, double r) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) return;
  MarkRect(Rect{p.x - r, p.y - r, p.x + r, p.y + r});
}

void Occupancy::MarkSegment(Point2d a, Point2d b, double r) {
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) return;
  // Clip roughly: skip segments wholly outside.
  if (std::max(a.x, b.x) < area_.x0 - r || std::min(a.x, b.x) > area_.x1 + r || std::max(a.y, b.y) < area_.y0 - r ||
      std::min(a.y, b.y) > area_.y1 + r)
    return;
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const int n = std::min(100000, static_cast<int>(std::ceil(len / (kCell / 2))));
  for (int k = 0; k <= n; ++k) {
    const double s = n ? static_cast<double>(k) / n : 0;
    MarkDisc(Point2d{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y)}, r);
  }
}

int Occupancy::Count(const Rect& r) const {
  int count = 0;
  for (int j = std::max(Cell(r.y0 - area_.y0), 0); j <= std::min(Cell(r.y1 - area_.y0), ny_ - 1); ++j)
    for (int i = std::max(Cell(r.x0 - area_.x0), 0); i <= std::min(Cell(r.x1 - area_.x0), nx_ - 1); ++i)
      count += cells_[static_cast<std::size_t>(j) * nx_ + i];
  return count;
}

LegendSize MeasureLegend(const std::vector<LegendEntry>& entries) {
  if (entries.empty()) return {};
  double row = 0;
  for (const auto& e : entries)
    row = std::max(row, e.marker == LegendMarker::kStartEnd
                            ? MarkerKey().width
                            : kLegendSample + 9 + MeasureText(e.name, {}, LegendStyle()).width());
  return LegendSize{2 * kLegendPad + row + 2, 2 * (kLegendPad - 4) + entries.size() * kLegendRow};
}

std::optional<Rect> LegendCorner(const Rect& area, LegendSize size, const Occupancy& data,
                                 const Occupancy* decoration) {
  const Rect& a = area;
  const double w = size.width, h = size.height;
  const Rect corners[4] = {
      {a.x1 - kLegendInset - w, a.y0 + kLegendInset, a.x1 - kLegendInset, a.y0 + kLegendInset + h},
      {a.x0 + kLegendInset, a.y0 + kLegendInset, a.x0 + kLegendInset + w, a.y0 + kLegendInset + h},
      {a.x1 - kLegendInset - w, a.y1 - kLegendInset - h, a.x1 - kLegendInset, a.y1 - kLegendInset},
      {a.x0 + kLegendInset, a.y1 - kLegendInset - h, a.x0 + kLegendInset + w, a.y1 - kLegendInset}};
  int best = -1;
  std::pair<int, int> best_score{std::numeric_limits<int>::max(), 0};
  for (int k = 0; k < 4; ++k) {
    const Rect& r = corners[k];
    if (r.x0 < a.x0 || r.x1 > a.x1 || r.y0 < a.y0 || r.y1 > a.y1) continue;
    const std::pair<int, int> score{data.Count(r.Inflated(4)), decoration ? decoration->Count(r.Inflated(4)) : 0};
    if (score < best_score) best = k, best_score = score;
  }
  if (best < 0 || best_score.first > 0) return std::nullopt;
  return corners[best];
}

Rect LegendRight(const Rect& area, LegendSize size) {
  return Rect{area.x1 + kLegendGap, area.y0, area.x1 + kLegendGap + size.width, area.y0 + size.height};
}

void DrawLegend(Renderer& r, const std::vector<LegendEntry>& entries, const Rect& box) {
  if (entries.empty()) return;
  r.FillRect(box, kLegendBorder);
  r.FillRect(box.Inflated(-1), kWhite);
  double y = box.y0 + kLegendPad - 4 + kLegendRow / 2;
  for (const auto& e : entries) {
    const double x = box.x0 + kLegendPad;
    const double yc = std::floor(y) + 0.5;
    if (e.marker == LegendMarker::kStartEnd) {
      const MarkerKeyRow k = MarkerKey();
      const double h = kMarkerRadius * std::sqrt(kPi) / 2;
      r.FillCircle({x + k.circle, yc}, kMarkerRadius, kMarkerKeyColor);
      r.DrawText("start", {x + k.start_text, yc}, LegendStyle());
      r.FillRect(Rect{x + k.square - h, yc - h, x + k.square + h, yc + h}, kMarkerKeyColor);
      r.DrawText("end", {x + k.end_text, yc}, LegendStyle());
    } else if (e.marker == LegendMarker::kDot) {
      r.FillCircle({x + kLegendSample / 2, yc}, kDotRadius, e.line.color);
      r.DrawText(e.name, {x + kLegendSample + 9, yc}, LegendStyle());
    } else {
      r.DrawPolyline({{x, yc}, {x + kLegendSample, yc}}, e.line);
      r.DrawText(e.name, {x + kLegendSample + 9, yc}, LegendStyle());
    }
    y += kLegendRow;
  }
}

}  // namespace twinsim::plot_style
