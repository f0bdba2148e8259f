#include "render/path3d_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/error.h"
#include "render/legend.h"
#include "render/plot.h"
#include "render/plot_style.h"

namespace twinsim {
namespace {

using namespace plot_style;


// Beyond the shared look (plot_style.h): what only the 3D view has.
constexpr double kTickSpacing = 70;   // px, at least, between ticks along a projected edge
constexpr double kShadowWidth = 1.5;  // the paths' shadows on the floor

constexpr Color kTickColor = Color::Hex(0x3a3a3a);
constexpr Color kBoxColor = Color::Hex(0xb4b4b4);
constexpr Color kShadowColor = Color::Hex(0xc8c8c8);

bool Finite(const Eigen::Vector3d& p) { return p.allFinite(); }

// The legend rows: each path's line sample and name, the shadows' when drawn, and the
// key to the start and end markers.
std::vector<LegendEntry> Legend(const Path3DPlot& plot) {
  std::vector<LegendEntry> out;
  bool any = false;
  for (std::size_t k = 0; k < plot.paths.size(); ++k) {
    LineStyle style = PlotLineStyle(static_cast<int>(k), kDataWidth);
    style.color = PlotColor(static_cast<int>(k));
    out.push_back(LegendEntry{plot.paths[k].name, style});
    any = any || !plot.paths[k].points.empty();
  }
  if (any && plot.show_projection)
    out.push_back(LegendEntry{"shadow on the floor", LineStyle{kShadowColor, kShadowWidth, {}, LineCap::kRound}});
  if (any) out.push_back(LegendEntry{"", {}, LegendMarker::kStartEnd});
  return out;
}

// The paths' box: every finite point with a margin of 5 % of the largest side (at
// least 2 cm); no side shorter than 30 % of the largest, so that flat paths (letters
// in a plane) still sit in a box that reads as 3D.
void DataBox(const Path3DPlot& plot, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  Eigen::Vector3d a = Eigen::Vector3d::Constant(INFINITY), b = Eigen::Vector3d::Constant(-INFINITY);
  for (const auto& path : plot.paths)
    for (const auto& p : path.points)
      if (Finite(p)) a = a.cwiseMin(p), b = b.cwiseMax(p);
  if (!(a.x() <= b.x())) a.setZero(), b.setOnes();
  const double side = std::max((b - a).maxCoeff(), 0.1);
  const double m = std::max(0.05 * side, 0.02);
  a.array() -= m;
  b.array() += m;
  for (int i = 0; i < 3; ++i) {
    const double grow = 0.3 * (side + 2 * m) - (b[i] - a[i]);
    if (grow > 0) a[i] -= grow / 2, b[i] += grow / 2;
  }
  *lo = a;
  *hi = b;
}

Eigen::Vector3d Corner(const Path3DLayout& L, int i) {
  return Eigen::Vector3d{i & 1 ? L.box_max.x() : L.box_min.x(), i & 2 ? L.box_max.y() : L.box_min.y(),
                         i & 4 ? L.box_max.z() : L.box_min.z()};
}

// Towards the viewer.
Eigen::Vector3d Eye(const Path3DLayout& L) {
  return Eigen::Vector3d{std::cos(L.elevation) * std::cos(L.azimuth), std::cos(L.elevation) * std::sin(L.azimuth),
                         std::sin(L.elevation)};
}

// The length in pixels of 1 m along world axis `axis`, at scale 1.
double Foreshortening(const Path3DLayout& L, int axis) {
  return std::hypot(L.Right()[axis], L.Up()[axis]);
}

struct Label {
  std::string text;
  Point2d anchor;
  TextStyle style;
  Rect rect;
};

// Everything drawn around the box: tick marks and their labels on two floor edges and
// one vertical edge, and the axis labels.
struct Decorations {
  std::vector<Point2d> ticks;  // segments
  std::vector<Label> labels;
  // Box edges by corner index pairs, the three at the corner nearest the viewer last.
  std::vector<std::pair<int, int>> edges;
  std::vector<Point2d> grid;   // segments on the back faces
};

// Half the extent of a w x h box along the unit direction d.
double HalfExtent(const Rect& r, Point2d d) { return std::abs(d.x) * r.width() / 2 + std::abs(d.y) * r.height() / 2; }

Decorations Decorate(const Path3DLayout& L) {
  Decorations D;
  const Eigen::Vector3d e = Eye(L);
  // Front and back sides along each axis (the viewer is on the front side).
  int front[3];
  for (int i = 0; i < 3; ++i) front[i] = e[i] > 1e-12 ? 1 : 0;
  auto side = [&](int axis, int s) { return s ? L.box_max[axis] : L.box_min[axis]; };

  for (int i = 0; i < 8; ++i)
    for (int axis = 0; axis < 3; ++axis)
      if (!(i & (1 << axis))) D.edges.push_back({i, i | (1 << axis)});
  const int nearest = front[0] | front[1] << 1 | front[2] << 2;
  std::stable_partition(D.edges.begin(), D.edges.end(),
                        [&](const auto& ed) { return ed.first != nearest && ed.second != nearest; });

  // Grid lines on the three back faces, at the ticks of the two axes in each face.
  for (int n = 0; n < 3; ++n) {
    const double at = side(n, 1 - front[n]);
    for (int a = 0; a < 3; ++a) {
      if (a == n) continue;
      const int b = 3 - n - a;  // the direction the line runs
      for (double t : Ticks(L.box_min[a], L.box_max[a], L.step[a])) {
        Eigen::Vector3d p0, p1;
        p0[n] = p1[n] = at;
        p0[a] = p1[a] = t;
        p0[b] = L.box_min[b];
        p1[b] = L.box_max[b];
        D.grid.push_back(L.ToPixel(p0));
        D.grid.push_back(L.ToPixel(p1));
      }
    }
  }

  auto unit = [](Point2d d, Point2d fallback) {
    const double n = std::hypot(d.x, d.y);
    return n > 1e-6 ? Point2d{d.x / n, d.y / n} : fallback;
  };
  // Ticks along world axis `axis` on the edge through `base` (its coordinate along `axis`
  // ignored), pointing along screen direction `out`; then the axis label beyond them.
  auto axis_ticks = [&](int axis, Eigen::Vector3d base, Point2d out, const std::string& name, bool vertical_label) {
    double reach = 0;
    std::vector<Rect> placed;
    for (double t : Ticks(L.box_min[axis], L.box_max[axis], L.step[axis])) {
      base[axis] = t;
      const Point2d p = L.ToPixel(base);
      const Point2d q{p.x + kTickLength * out.x, p.y + kTickLength * out.y};
      const std::string text = FormatTick(t, L.step[axis]);
      const Rect size = MeasureText(text, {}, TickStyle(VAlign::kMiddle));
      const double h = HalfExtent(size, out);
      const Point2d anchor{std::round(q.x + out.x * (kTickGap + h)), std::round(q.y + out.y * (kTickGap + h))};
      const Rect r = MeasureText(text, anchor, TickStyle(VAlign::kMiddle));
      bool clash = false;
      for (const Rect& o : placed) clash = clash || o.Inflated(3).Intersects(r);
      D.ticks.insert(D.ticks.end(), {p, q});
      if (clash) continue;
      placed.push_back(r);
      D.labels.push_back(Label{text, anchor, TickStyle(VAlign::kMiddle), r});
      reach = std::max(reach, kTickGap + 2 * h);
    }
    Eigen::Vector3d mid = base;
    mid[axis] = (L.box_min[axis] + L.box_max[axis]) / 2;
    const Point2d p = L.ToPixel(mid);
    TextStyle s = LabelStyle(VAlign::kMiddle);
    s.vertical = vertical_label;
    const Rect size = MeasureText(name, {}, s);
    const double d = kTickLength + reach + kLabelGap + HalfExtent(size, out);
    const Point2d anchor{std::round(p.x + out.x * d), std::round(p.y + out.y * d)};
    D.labels.push_back(Label{name, anchor, s, MeasureText(name, anchor, s)});
  };
  // x and y on the floor's front edges, pointing away from the box.
  const double floor = L.box_min.z();
  for (int axis : {0, 1}) {
    const int other = 1 - axis;
    Eigen::Vector3d base;
    base[other] = side(other, front[other]);
    base[2] = floor;
    Eigen::Vector3d away = Eigen::Vector3d::Zero();
    away[other] = front[other] ? 1 : -1;
    const Point2d o = L.ToPixel(Eigen::Vector3d::Zero()), a = L.ToPixel(away);
    Point2d out = unit(Point2d{a.x - o.x, a.y - o.y}, Point2d{0, 1});
    if (out.y < 0 && std::abs(out.y) > std::abs(out.x)) out = Point2d{0, 1};  // never up into the box
    axis_ticks(axis, base, out, axis == 0 ? "x [m]" : "y [m]", false);
  }
  // z on the vertical edge of the side corner further right, pointing right.
  Eigen::Vector3d c1{side(0, front[0]), side(1, 1 - front[1]), 0};
  Eigen::Vector3d c2{side(0, 1 - front[0]), side(1, front[1]), 0};
  const bool right1 = L.ToPixel(c1).x >= L.ToPixel(c2).x;
  const Eigen::Vector3d zc = right1 ? c1 : c2;
  axis_ticks(2, zc, Point2d{1, 0}, "z [m]", true);
  return D;
}

void CheckInput(const Path3DPlot& plot) {
  if (plot.width < 240 || plot.height < 180 || plot.width > 8192 || plot.height > 8192)
    throw InputError("plot size " + std::to_string(plot.width) + " x " + std::to_string(plot.height) +
                     " px is outside 240..8192 x 180..8192");
  if (!(std::abs(plot.elevation_deg) <= 90) || !std::isfinite(plot.azimuth_deg))
    throw InputError("3D plot view: elevation must be in -90..90 degrees and azimuth finite");
}

Rect Union(const Rect& a, const Rect& b) {
  return Rect{std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

// The projected box and everything drawn around it.
Rect Extent(const Path3DLayout& L, const Decorations& D, Rect* box) {
  Rect b{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (int i = 0; i < 8; ++i) {
    const Point2d p = L.ToPixel(Corner(L, i));
    b = Union(b, Rect{p.x, p.y, p.x, p.y});
  }
  *box = b;
  for (const Label& l : D.labels) b = Union(b, l.rect);
  return b;
}

// The data's pixels (paths, shadows, markers), for the legend to avoid.
void MarkData(const Path3DPlot& plot, const Path3DLayout& L, Occupancy* occ) {
  const double marker = kMarkerRadius + kMarkerStep * std::max<int>(0, static_cast<int>(plot.paths.size()) - 1) + kMarkerRing + 1;
  for (const auto& path : plot.paths) {
    const Eigen::Vector3d* first = nullptr;
    const Eigen::Vector3d* last = nullptr;
    for (std::size_t i = 0; i < path.points.size(); ++i) {
      const Eigen::Vector3d& p = path.points[i];
      if (!Finite(p)) continue;
      if (!first) first = &p;
      last = &p;
      if (i + 1 < path.points.size() && Finite(path.points[i + 1])) {
        occ->MarkSegment(L.ToPixel(p), L.ToPixel(path.points[i + 1]), kDataWidth);
        if (plot.show_projection) {
          const Eigen::Vector3d a{p.x(), p.y(), L.box_min.z()};
          const Eigen::Vector3d b{path.points[i + 1].x(), path.points[i + 1].y(), L.box_min.z()};
          occ->MarkSegment(L.ToPixel(a), L.ToPixel(b), kShadowWidth);
        }
      }
    }
    for (const Eigen::Vector3d* p : {first, last})
      if (p) occ->MarkSegment(L.ToPixel(*p), L.ToPixel(*p), marker);
  }
}

Path3DLayout Layout(const Path3DPlot& plot, bool legend_outside) {
  CheckInput(plot);
  Path3DLayout L;
  L.width = plot.width;
  L.height = plot.height;
  L.azimuth = plot.azimuth_deg * kPi / 180;
  L.elevation = plot.elevation_deg * kPi / 180;
  DataBox(plot, &L.box_min, &L.box_max);
  const std::vector<LegendEntry> legend_entries = Legend(plot);
  const LegendSize legend = MeasureLegend(legend_entries);
  const double title_h = plot.title.empty() ? 0 : MeasureText(plot.title, {}, TitleStyle()).height();

  Rect& a = L.plot_area;
  a.x0 = kOuterPad;
  a.x1 = plot.width - kOuterPad - (legend_outside ? legend.width + kLegendGap : 0);
  a.y0 = std::round(kOuterPad + (title_h > 0 ? title_h + kTitleGap : 6));
  a.y1 = plot.height - kOuterPad;
  if (a.width() < 80 || a.height() < 80) throw InputError("plot too small for its labels");

  // The box at scale 1; then the scale that fits box and labels (their size in pixels
  // does not grow with the scale, but the ticks' step does: iterate).
  L.scale = 1;
  L.origin = {0, 0};
  Rect unit_box;
  Extent(L, Decorations{}, &unit_box);
  L.scale = 0.8 * std::min(a.width() / unit_box.width(), a.height() / unit_box.height());
  Decorations D;
  Rect box, all;
  for (int iteration = 0; iteration < 8; ++iteration) {
    for (int i = 0; i < 3; ++i)
      L.step[i] = NiceStep(kTickSpacing / (L.scale * std::max(Foreshortening(L, i), 0.25)));
    D = Decorate(L);
    all = Extent(L, D, &box);
    const double extra_x = all.width() - box.width(), extra_y = all.height() - box.height();
    // 2 px to spare: the centring below rounds to whole pixels.
    const double s = std::min((a.width() - extra_x - 2) / unit_box.width(), (a.height() - extra_y - 2) / unit_box.height());
    if (!(s > 0)) throw InputError("plot too small for its labels");
    const bool stable = std::abs(s - L.scale) < 1e-3 * L.scale;
    L.scale = s;
    if (stable) break;
  }
  D = Decorate(L);
  all = Extent(L, D, &box);
  // Centre the box and its labels in the plot area, on whole pixels.
  L.origin.x += std::round((a.x0 + a.x1) / 2 - (all.x0 + all.x1) / 2);
  L.origin.y += std::round((a.y0 + a.y1) / 2 - (all.y0 + all.y1) / 2);
  D = Decorate(L);
  all = Extent(L, D, &L.box);
  if (!plot.title.empty()) L.title = MeasureText(plot.title, Point2d{(a.x0 + a.x1) / 2, kOuterPad}, TitleStyle());

  if (legend_entries.empty()) return L;
  if (legend_outside) {
    L.legend_inside = false;
    L.legend = LegendRight(a, legend);
    return L;
  }
  // The corner with no data under it and the fewest box edges and labels; top right,
  // top left, bottom right, bottom left in that order of preference.
  Occupancy data(a), decoration(a);
  MarkData(plot, L, &data);
  for (const auto& [i, j] : D.edges) decoration.MarkSegment(L.ToPixel(Corner(L, i)), L.ToPixel(Corner(L, j)), 1);
  for (const Label& l : D.labels) decoration.MarkRect(l.rect);
  const std::optional<Rect> corner = LegendCorner(a, legend, data, &decoration);
  if (!corner) return Layout(plot, true);
  L.legend = *corner;
  return L;
}

}  // namespace

Eigen::Vector3d Path3DLayout::Right() const { return Eigen::Vector3d{-std::sin(azimuth), std::cos(azimuth), 0}; }

Eigen::Vector3d Path3DLayout::Up() const {
  return Eigen::Vector3d{-std::sin(elevation) * std::cos(azimuth), -std::sin(elevation) * std::sin(azimuth),
                         std::cos(elevation)};
}

Point2d Path3DLayout::ToPixel(const Eigen::Vector3d& p) const {
  return Point2d{origin.x + scale * p.dot(Right()), origin.y - scale * p.dot(Up())};
}

Path3DLayout LayoutPath3DPlot(const Path3DPlot& plot) { return Layout(plot, false); }

RgbaImage RenderPath3DPlot(const Path3DPlot& plot, Renderer& renderer, Path3DLayout* layout) {
  const Path3DLayout L = Layout(plot, false);
  if (layout) *layout = L;
  const Decorations D = Decorate(L);
  Renderer& r = renderer;
  r.Begin(plot.width, plot.height, kWhite);

  // Back to front, without hidden-line removal: grid and box, shadows, paths, markers.
  r.DrawSegments(D.grid, LineStyle{kGridColor, 1.0, {}, LineCap::kButt});
  std::vector<Point2d> edges;
  for (const auto& [i, j] : D.edges) edges.insert(edges.end(), {L.ToPixel(Corner(L, i)), L.ToPixel(Corner(L, j))});
  r.DrawSegments(edges, LineStyle{kBoxColor, 1.0, {}, LineCap::kRound});
  r.DrawSegments(D.ticks, LineStyle{kTickColor, 1.0, {}, LineCap::kButt});

  const int n = static_cast<int>(plot.paths.size());
  if (plot.show_projection)
    for (int k = 0; k < n; ++k) {
      LineStyle style = PlotLineStyle(k, kShadowWidth);
      style.color = kShadowColor;
      std::vector<Point2d> px;
      for (const auto& p : plot.paths[k].points)
        px.push_back(Finite(p) ? L.ToPixel(Eigen::Vector3d{p.x(), p.y(), L.box_min.z()}) : Point2d{NAN, NAN});
      r.DrawPolyline(px, style);
    }
  std::vector<std::optional<Point2d>> starts(n), ends(n);
  for (int k = 0; k < n; ++k) {
    LineStyle style = PlotLineStyle(k, kDataWidth);
    style.color = PlotColor(k);
    std::vector<Point2d> px;
    for (const auto& p : plot.paths[k].points) {
      px.push_back(Finite(p) ? L.ToPixel(p) : Point2d{NAN, NAN});
      if (Finite(p)) {
        if (!starts[k]) starts[k] = px.back();
        ends[k] = px.back();
      }
    }
    r.DrawPolyline(px, style);
  }
  // Markers on top of every line.
  DrawStartEndMarkers(r, starts, ends);

  for (const Label& l : D.labels) r.DrawText(l.text, l.anchor, l.style);
  if (!plot.title.empty())
    r.DrawText(plot.title, {(L.plot_area.x0 + L.plot_area.x1) / 2, L.title.y0}, TitleStyle());
  DrawLegend(r, Legend(plot), L.legend);
  return r.Finish();
}

}  // namespace twinsim
