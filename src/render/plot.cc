#include "render/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "core/error.h"
#include "render/legend.h"
#include "render/plot_style.h"

namespace twinsim {
namespace {

using namespace plot_style;

// Beyond the shared look (plot_style.h): what only the 2D plots have.
constexpr double kDataPad = 16;      // room around fitted data for markers and ticks
constexpr double kHeadingTick = 11;  // length of a heading tick
constexpr double kHeadingWidth = 1.3;
constexpr double kHeadingSpacing = 30;  // automatic heading ticks: about this far apart along a path

constexpr Color kFrameColor = Color::Hex(0x3a3a3a);
constexpr Color kFieldColor = Color::Hex(0x9a9a9a);

// Okabe & Ito (2008), "Color Universal Design": blue, vermillion, bluish green, reddish
// purple, orange, sky blue, black; yellow last, it is faint on white.
constexpr std::uint32_t kPalette[] = {0x0072b2, 0xd55e00, 0x009e73, 0xcc79a7, 0xe69f00, 0x56b4e9, 0x000000, 0xf0e442};

// What both kinds of plot share: text, the range to show, the legend, and where the
// data lies (in world units) so that the legend can avoid it.
struct Chart {
  std::string title, x_label, y_label;
  int width = 0, height = 0;
  bool equal_aspect = false;
  WorldRect view;        // to show at least
  double data_pad = 0;   // px kept free around `view` (equal aspect only)
  std::vector<LegendEntry> legend;
  std::vector<std::vector<Pose2>> occupied_lines;  // world; theta unused
  std::vector<std::pair<Pose2, double>> occupied_discs;  // world centre, radius in px
};


// The centre of the pixel a 1 px line at coordinate v should light.
double Snap(double v) { return std::floor(v) + 0.5; }

void CheckSize(int width, int height) {
  if (width < 240 || height < 180 || width > 8192 || height > 8192)
    throw InputError("plot size " + std::to_string(width) + " x " + std::to_string(height) +
                     " px is outside 240..8192 x 180..8192");
}

// `step` (a 1, 2 or 5 x 10^n), made finer (5 -> 2 -> 1 -> 0.5) until [lo, hi] holds at
// least two ticks: an axis with one labelled value has no scale. Where 70 px between
// ticks asks a step just over 2 x 10^n, 5 x 10^n can leave a range of twice that with
// 0 alone (a turn rate of +-0.42 rad/s on a 290 px axis: a step of 0.5).
double StepWithTwoTicks(double lo, double hi, double step) {
  for (int k = 0; k < 6 && Ticks(lo, hi, step).size() < 2; ++k) {
    const double e = std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    const double m = step / e;  // 1, 2 or 5
    step = m > 4 ? 2 * e : m > 1.5 ? e : 0.5 * e;
  }
  return step;
}

PlotLayout LayoutChart(const Chart& c, bool legend_outside) {
  CheckSize(c.width, c.height);
  PlotLayout L;
  L.width = c.width;
  L.height = c.height;
  const double title_h = c.title.empty() ? 0 : MeasureText(c.title, {}, TitleStyle()).height();
  const double label_h = MeasureText("Xy", {}, LabelStyle()).height();
  const double tick_h = MeasureText("0", {}, TickStyle()).height();
  const LegendSize legend = MeasureLegend(c.legend);
  double y_labels_w = MeasureText("\u22120.0", {}, TickStyle()).width();
  double x_label_half = 12;

  for (int iteration = 0; iteration < 5; ++iteration) {
    Rect area;
    area.x0 = std::round(kOuterPad + (c.y_label.empty() ? 0 : label_h + kLabelGap) + y_labels_w + kTickGap + kTickLength);
    area.x1 = std::round(c.width - kOuterPad - std::max(0.0, x_label_half - kOuterPad + 4) -
                         (legend_outside ? legend.width + kLegendGap : 0));
    area.y0 = std::round(kOuterPad + (title_h > 0 ? title_h + kTitleGap : 6));
    area.y1 = std::round(c.height - kOuterPad - (c.x_label.empty() ? 0 : label_h + kLabelGap) - tick_h - kTickGap -
                         kTickLength);
    if (area.width() < 40 || area.height() < 40) throw InputError("plot too small for its labels");
    L.plot_area = area;

    WorldRect v = c.view;
    if (c.equal_aspect) {
      const double dx = std::max(v.x_max - v.x_min, 1e-9), dy = std::max(v.y_max - v.y_min, 1e-9);
      const double scale = std::min((area.width() - 2 * c.data_pad) / dx, (area.height() - 2 * c.data_pad) / dy);
      const double cx = (v.x_min + v.x_max) / 2, cy = (v.y_min + v.y_max) / 2;
      v = WorldRect{cx - area.width() / 2 / scale, cx + area.width() / 2 / scale, cy - area.height() / 2 / scale,
                    cy + area.height() / 2 / scale};
    }
    L.view = v;
    const double x_scale = area.width() / (v.x_max - v.x_min);   // px per unit
    const double y_scale = area.height() / (v.y_max - v.y_min);
    L.x_step = StepWithTwoTicks(v.x_min, v.x_max, NiceStep(95 / x_scale));
    L.y_step = StepWithTwoTicks(v.y_min, v.y_max, c.equal_aspect ? L.x_step : NiceStep(70 / y_scale));
    if (c.equal_aspect) L.x_step = L.y_step;  // no coarser than x's: both axes keep two ticks

    double new_y_w = 0;
    for (double t : Ticks(v.y_min, v.y_max, L.y_step))
      new_y_w = std::max(new_y_w, MeasureText(FormatTick(t, L.y_step), {}, TickStyle()).width());
    const std::vector<double> xt = Ticks(v.x_min, v.x_max, L.x_step);
    double new_half = 0;
    if (!xt.empty()) {
      const double last_px = L.ToPixel(xt.back(), v.y_min).x;
      new_half = last_px + MeasureText(FormatTick(xt.back(), L.x_step), {}, TickStyle()).width() / 2 - area.x1;
    }
    const bool stable = std::abs(new_y_w - y_labels_w) < 0.5 && std::abs(new_half - x_label_half) < 0.5;
    y_labels_w = new_y_w;
    x_label_half = std::max(new_half, 0.0);
    if (stable) break;
  }

  const Rect& a = L.plot_area;
  if (!c.title.empty()) L.title = MeasureText(c.title, Point2d{(a.x0 + a.x1) / 2, kOuterPad}, TitleStyle());
  // The axes' boxes: frame to tick labels to axis label, as wide as their tick labels reach.
  double x_lo = a.x0, x_hi = a.x1, y_lo = a.y0, y_hi = a.y1;
  for (double t : Ticks(L.view.x_min, L.view.x_max, L.x_step)) {
    const Rect r = MeasureText(FormatTick(t, L.x_step), {L.ToPixel(t, 0).x, 0}, TickStyle());
    x_lo = std::min(x_lo, r.x0), x_hi = std::max(x_hi, r.x1);
  }
  TextStyle y_tick = TickStyle();
  y_tick.valign = VAlign::kMiddle;
  for (double t : Ticks(L.view.y_min, L.view.y_max, L.y_step)) {
    const Rect r = MeasureText(FormatTick(t, L.y_step), {0, L.ToPixel(0, t).y}, y_tick);
    y_lo = std::min(y_lo, r.y0), y_hi = std::max(y_hi, r.y1);
  }
  L.x_axis = Rect{std::max(x_lo, 0.0), a.y1 + 1, std::min(x_hi, double(c.width)),
                  a.y1 + 1 + kTickLength + kTickGap + tick_h + (c.x_label.empty() ? 0 : kLabelGap + label_h)};
  L.y_axis = Rect{a.x0 - 1 - kTickLength - kTickGap - y_labels_w - (c.y_label.empty() ? 0 : kLabelGap + label_h),
                  std::max(y_lo, 0.0), a.x0 - 1, std::min(y_hi, double(c.height))};

  if (c.legend.empty()) return L;
  if (legend_outside) {
    L.legend_inside = false;
    L.legend = LegendRight(a, legend);
    return L;
  }
  // A corner free of data (LegendCorner), else outside on the right.
  Occupancy occ(a);
  for (const auto& line : c.occupied_lines) {
    for (std::size_t i = 0; i + 1 < line.size(); ++i)
      occ.MarkSegment(L.ToPixel(line[i].x, line[i].y), L.ToPixel(line[i + 1].x, line[i + 1].y), kDataWidth);
    if (line.size() == 1) occ.MarkDisc(L.ToPixel(line[0].x, line[0].y), kDataWidth);
  }
  Point2d previous{NAN, NAN};
  double previous_r = -1;
  for (const auto& [p, r] : c.occupied_discs) {
    // Dense paths put many discs on the same spot: mark each spot once.
    const Point2d q = L.ToPixel(p.x, p.y);
    if (r == previous_r && std::abs(q.x - previous.x) < 1 && std::abs(q.y - previous.y) < 1) continue;
    occ.MarkDisc(q, r);
    previous = q;
    previous_r = r;
  }
  const std::optional<Rect> corner = LegendCorner(a, legend, occ);
  if (!corner) return LayoutChart(c, true);
  L.legend = *corner;
  return L;
}

// Grid lines at the ticks, drawn under the data.
void DrawGrid(const PlotLayout& L, Renderer& r) {
  const Rect& a = L.plot_area;
  std::vector<Point2d> grid;
  for (double t : Ticks(L.view.x_min, L.view.x_max, L.x_step)) {
    const double x = Snap(L.ToPixel(t, 0).x);
    if (x > a.x0 + 1 && x < a.x1 - 1) grid.insert(grid.end(), {{x, a.y0}, {x, a.y1}});
  }
  for (double t : Ticks(L.view.y_min, L.view.y_max, L.y_step)) {
    const double y = Snap(L.ToPixel(0, t).y);
    if (y > a.y0 + 1 && y < a.y1 - 1) grid.insert(grid.end(), {{a.x0, y}, {a.x1, y}});
  }
  r.DrawSegments(grid, LineStyle{kGridColor, 1.0, {}, LineCap::kButt});
}

void DrawAxes(const Chart& c, const PlotLayout& L, Renderer& r) {
  const Rect& a = L.plot_area;
  // The frame just outside the plot area, so it never covers data.
  r.FillRect(Rect{a.x0 - 1, a.y0 - 1, a.x1 + 1, a.y0}, kFrameColor);
  r.FillRect(Rect{a.x0 - 1, a.y1, a.x1 + 1, a.y1 + 1}, kFrameColor);
  r.FillRect(Rect{a.x0 - 1, a.y0, a.x0, a.y1}, kFrameColor);
  r.FillRect(Rect{a.x1, a.y0, a.x1 + 1, a.y1}, kFrameColor);
  TextStyle tick = TickStyle();
  for (double t : Ticks(L.view.x_min, L.view.x_max, L.x_step)) {
    const double x = Snap(L.ToPixel(t, 0).x);
    r.FillRect(Rect{x - 0.5, a.y1 + 1, x + 0.5, a.y1 + 1 + kTickLength}, kFrameColor);
    tick.halign = HAlign::kCenter;
    tick.valign = VAlign::kTop;
    r.DrawText(FormatTick(t, L.x_step), {x, a.y1 + 1 + kTickLength + kTickGap}, tick);
  }
  for (double t : Ticks(L.view.y_min, L.view.y_max, L.y_step)) {
    const double y = Snap(L.ToPixel(0, t).y);
    r.FillRect(Rect{a.x0 - 1 - kTickLength, y - 0.5, a.x0 - 1, y + 0.5}, kFrameColor);
    tick.halign = HAlign::kRight;
    tick.valign = VAlign::kMiddle;
    r.DrawText(FormatTick(t, L.y_step), {a.x0 - 1 - kTickLength - kTickGap, y}, tick);
  }
  if (!c.x_label.empty()) {
    TextStyle s = LabelStyle();
    s.valign = VAlign::kBottom;
    r.DrawText(c.x_label, {(a.x0 + a.x1) / 2, L.x_axis.y1}, s);
  }
  if (!c.y_label.empty()) {
    TextStyle s = LabelStyle();
    s.vertical = true;
    s.valign = VAlign::kTop;
    r.DrawText(c.y_label, {L.y_axis.x0, (a.y0 + a.y1) / 2}, s);
  }
  if (!c.title.empty()) r.DrawText(c.title, {(a.x0 + a.x1) / 2, L.title.y0}, TitleStyle());
}

RgbaImage DrawChart(const Chart& c, const PlotLayout& L, Renderer& r, const std::function<void()>& draw_data) {
  r.Begin(c.width, c.height, kWhite);
  r.SetClip(L.plot_area);
  DrawGrid(L, r);
  draw_data();
  r.ResetClip();
  DrawAxes(c, L, r);
  DrawLegend(r, c.legend, L.legend);
  return r.Finish();
}

// The largest start or end marker of n paths (all at one place), with its white ring.
double MaxMarkerReach(int n) { return kMarkerRadius + kMarkerStep * std::max(0, n - 1) + kMarkerRing; }

bool Finite(const Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// The frames between heading ticks on a path: given, or about kHeadingSpacing px apart.
int HeadingEvery(const PathPlot& plot, const PlotPath& path, const PlotLayout& L) {
  if (plot.orientation_every >= 0) return plot.orientation_every;
  double length = 0;
  int n = 0;
  for (std::size_t i = 0; i + 1 < path.poses.size(); ++i) {
    if (!Finite(path.poses[i]) || !Finite(path.poses[i + 1])) continue;
    const Point2d a = L.ToPixel(path.poses[i].x, path.poses[i].y), b = L.ToPixel(path.poses[i + 1].x, path.poses[i + 1].y);
    length += std::hypot(b.x - a.x, b.y - a.y);
    ++n;
  }
  if (length < kHeadingSpacing) return 0;
  return std::max(1, static_cast<int>(std::lround(n * kHeadingSpacing / length)));
}

Chart PathChart(const PathPlot& plot) {
  Chart c;
  c.title = plot.title;
  c.x_label = plot.x_label;
  c.y_label = plot.y_label;
  c.width = plot.width;
  c.height = plot.height;
  c.equal_aspect = true;
  if (plot.region && (!(plot.region->x_max > plot.region->x_min) || !(plot.region->y_max > plot.region->y_min)))
    throw InputError("plot region must have x_min < x_max and y_min < y_max");
  if (plot.region) {
    c.view = *plot.region;
    c.data_pad = 0;
  } else {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const auto& p : plot.paths)
      for (const auto& q : p.poses)
        if (Finite(q)) {
          x0 = std::min(x0, q.x), x1 = std::max(x1, q.x);
          y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
        }
    if (!(x0 <= x1)) {
      x0 = y0 = -1;
      x1 = y1 = 1;
    }
    // A margin of 5 % of the larger side (at least 5 cm), plus room for markers in pixels.
    const double m = std::max(0.05 * std::max(x1 - x0, y1 - y0), 0.05);
    c.view = WorldRect{x0 - m, x1 + m, y0 - m, y1 + m};
    c.data_pad = kDataPad;
  }
  for (std::size_t k = 0; k < plot.paths.size(); ++k) {
    const PlotPath& p = plot.paths[k];
    LineStyle style = PlotLineStyle(static_cast<int>(k), kDataWidth);
    style.color = PlotColor(static_cast<int>(k));
    c.legend.push_back(LegendEntry{p.name, style});
    c.occupied_lines.push_back(p.poses);
    // Heading ticks may reach kHeadingTick px from a pose; which poses get one is only
    // known once the scale is, so keep room around every pose.
    const double reach = plot.orientation_every == 0 ? kDataWidth : kHeadingTick + 1;
    const Pose2* last = nullptr;
    for (const auto& q : p.poses)
      if (Finite(q)) {
        if (!last) c.occupied_discs.push_back({q, MaxMarkerReach(static_cast<int>(plot.paths.size())) + 1});
        c.occupied_discs.push_back({q, reach});
        last = &q;
      }
    if (last) c.occupied_discs.push_back({*last, MaxMarkerReach(static_cast<int>(plot.paths.size())) + 1});
  }
  bool any = false;
  for (const auto& p : plot.paths) any = any || !p.poses.empty();
  if (any) c.legend.push_back(LegendEntry{"", {}, LegendMarker::kStartEnd});
  return c;
}

// The k-th series' line style: its own colour as a thin solid line, or the palette's
// next (counting only the series without a colour of their own).
LineStyle SeriesStyle(const SeriesPlot& plot, std::size_t k) {
  const PlotSeries& s = plot.series[k];
  if (s.color) return LineStyle{Color::Hex(*s.color), 1.0, {}, LineCap::kButt};
  int index = 0;
  for (std::size_t i = 0; i < k; ++i) index += plot.series[i].color ? 0 : 1;
  LineStyle style = PlotLineStyle(index, kDataWidth);
  style.color = PlotColor(index);
  return style;
}

Chart SeriesChart(const SeriesPlot& plot) {
  Chart c;
  c.title = plot.title;
  c.x_label = plot.x_label;
  c.y_label = plot.y_label;
  c.width = plot.width;
  c.height = plot.height;
  c.equal_aspect = false;
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (std::size_t k = 0; k < plot.series.size(); ++k) {
    const PlotSeries& s = plot.series[k];
    std::vector<Pose2> line;
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      line.push_back(Pose2{s.x[i], s.y[i], 0});
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
        y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
      }
    }
    c.occupied_lines.push_back(std::move(line));
    if (s.legend) c.legend.push_back(LegendEntry{s.name, SeriesStyle(plot, k), s.points ? LegendMarker::kDot : LegendMarker::kLine});
  }
  if (plot.range) {
    c.view = *plot.range;
  } else {
    if (!(x0 <= x1)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
    if (y1 - y0 < 1e-12) {
      const double m = std::max(std::abs(y0) * 0.1, 0.5);
      y0 -= m, y1 += m;
    }
    const double m = 0.05 * (y1 - y0);
    c.view = WorldRect{x0, x1, y0 - m, y1 + m};
  }
  if (!(c.view.x_max > c.view.x_min) || !(c.view.y_max > c.view.y_min))
    throw InputError("series plot range must have x_min < x_max and y_min < y_max");
  return c;
}

}  // namespace

Point2d PlotLayout::ToPixel(double x, double y) const {
  return Point2d{plot_area.x0 + (x - view.x_min) / (view.x_max - view.x_min) * plot_area.width(),
                 plot_area.y1 - (y - view.y_min) / (view.y_max - view.y_min) * plot_area.height()};
}

void PlotLayout::FromPixel(Point2d p, double* x, double* y) const {
  *x = view.x_min + (p.x - plot_area.x0) / plot_area.width() * (view.x_max - view.x_min);
  *y = view.y_min + (plot_area.y1 - p.y) / plot_area.height() * (view.y_max - view.y_min);
}

Color PlotColor(int k) { return Color::Hex(kPalette[((k % 8) + 8) % 8]); }

LineStyle PlotLineStyle(int k, double width) {
  LineStyle s;
  s.width = width;
  s.cap = LineCap::kRound;
  const double w = width;
  // Lengths along the centre line; round caps add w/2 at each end of every dash.
  switch (((k % 4) + 4) % 4) {
    case 0: break;
    case 1: s.dash = {4.0 * w, 3.4 * w}; break;
    case 2:  // dots look lighter than lines of the same width: make them a little wider
      s.width = 1.3 * w;
      s.dash = {0.01, 2.1 * s.width};
      break;
    case 3: s.dash = {4.0 * w, 2.6 * w, 0.5 * w, 2.6 * w}; break;
  }
  return s;
}

double NiceStep(double min_step) {
  if (!(min_step > 0) || !std::isfinite(min_step)) return 1;
  const double e = std::pow(10.0, std::floor(std::log10(min_step)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * e >= min_step * (1 - 1e-9)) return m * e;
  return 10 * e;
}

PlotLayout LayoutPathPlot(const PathPlot& plot) { return LayoutChart(PathChart(plot), false); }

PlotLayout LayoutSeriesPlot(const SeriesPlot& plot) { return LayoutChart(SeriesChart(plot), false); }

RgbaImage RenderPathPlot(const PathPlot& plot, Renderer& renderer, PlotLayout* layout) {
  const Chart c = PathChart(plot);
  const PlotLayout L = LayoutChart(c, false);
  if (layout) *layout = L;
  return DrawChart(c, L, renderer, [&] {
    if (plot.field) {
      const WorldRect& f = *plot.field;
      std::vector<Point2d> outline;
      for (const auto& [x, y] : {std::pair{f.x_min, f.y_min}, {f.x_max, f.y_min}, {f.x_max, f.y_max},
                                 {f.x_min, f.y_max}, {f.x_min, f.y_min}})
        outline.push_back(L.ToPixel(x, y));
      renderer.DrawPolyline(outline, LineStyle{kFieldColor, 1.5, {}, LineCap::kRound});
    }
    for (std::size_t k = 0; k < plot.paths.size(); ++k) {
      const PlotPath& p = plot.paths[k];
      const Color color = PlotColor(static_cast<int>(k));
      LineStyle style = PlotLineStyle(static_cast<int>(k), kDataWidth);
      style.color = color;
      std::vector<Point2d> px;
      px.reserve(p.poses.size());
      for (const auto& q : p.poses)
        px.push_back(Finite(q) ? L.ToPixel(q.x, q.y) : Point2d{NAN, NAN});
      renderer.DrawPolyline(px, style);
      const int every = HeadingEvery(plot, p, L);
      if (every > 0) {
        std::vector<Point2d> ticks;
        for (std::size_t i = 0; i < p.poses.size(); ++i) {
          const int frame = p.frames.size() == p.poses.size() ? p.frames[i] : static_cast<int>(i);
          if (frame % every != 0 || !Finite(p.poses[i]) || !std::isfinite(p.poses[i].theta)) continue;
          const Point2d a = px[i];
          // y is down in pixels: a heading theta points at (cos, -sin).
          ticks.push_back(a);
          ticks.push_back(Point2d{a.x + kHeadingTick * std::cos(p.poses[i].theta),
                                  a.y - kHeadingTick * std::sin(p.poses[i].theta)});
        }
        renderer.DrawSegments(ticks, LineStyle{color, kHeadingWidth, {}, LineCap::kButt});
      }
    }
    // Markers on top of every line; where paths start or end at the same place, earlier
    // paths' markers are larger, so that each shows as a ring around the later ones.
    const int n = static_cast<int>(plot.paths.size());
    std::vector<std::optional<Point2d>> starts(n), ends(n);
    for (int k = 0; k < n; ++k)
      for (const auto& q : plot.paths[k].poses)
        if (Finite(q)) {
          if (!starts[k]) starts[k] = L.ToPixel(q.x, q.y);
          ends[k] = L.ToPixel(q.x, q.y);
        }
    DrawStartEndMarkers(renderer, starts, ends);
  });
}

RgbaImage RenderSeriesPlot(const SeriesPlot& plot, Renderer& renderer, PlotLayout* layout) {
  const Chart c = SeriesChart(plot);
  const PlotLayout L = LayoutChart(c, false);
  if (layout) *layout = L;
  return DrawChart(c, L, renderer, [&] {
    for (std::size_t k = 0; k < plot.series.size(); ++k) {
      const PlotSeries& s = plot.series[k];
      const LineStyle style = SeriesStyle(plot, k);
      std::vector<Point2d> px;
      for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
        px.push_back(std::isfinite(s.x[i]) && std::isfinite(s.y[i]) ? L.ToPixel(s.x[i], s.y[i]) : Point2d{NAN, NAN});
      if (!s.points) {
        renderer.DrawPolyline(px, style);
        continue;
      }
      for (const Point2d& p : px)
        if (std::isfinite(p.x)) renderer.FillCircle(p, kDotRadius, style.color);
    }
  });
}

}  // namespace twinsim
