// Plots in world units, drawn through a Renderer into an RGBA image.
//
// A path plot shows robot paths on the field (or a region of it) in metres, with equal
// aspect ratio: every path in its own colour-blind-safe colour (Okabe-Ito) and line
// style (solid, dashed, dotted, dash-dot), its heading as short ticks every N frames,
// a circle where it starts and a square where it ends. A series plot shows several
// series against time (learning curves, errors, torques) with the same look. Both get a
// bold title, axes with ticks at 1, 2 or 5 x 10^n and unit labels, light grey grid
// lines, and a legend in the plot's emptiest corner (outside on the right when no
// corner is free of data). Data is clipped to the plot area; nothing else is drawn there
// except the grid, the field outline and the legend, which never covers data.
//
//   PathPlot plot;
//   plot.title = "drive45";
//   plot.paths.push_back({"truth", poses});
//   RgbaImage image = RenderPathPlot(plot, *MakeDefaultRenderer());
//
// LayoutPathPlot()/LayoutSeriesPlot() give the geometry without drawing: where the plot
// area, axes, title and legend are, and the world-to-pixel mapping (for tests).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "io/png_image.h"
#include "render/renderer.h"

namespace twinsim {

// A rectangle in world or data units.
struct WorldRect {
  double x_min = 0, x_max = 1;
  double y_min = 0, y_max = 1;
};

struct PlotPath {
  std::string name;           // legend entry
  std::vector<Pose2> poses;   // m, m, rad; non-finite poses break the line
  std::vector<int> frames;    // frame number of each pose, for the heading ticks (empty: 0, 1, 2, ...)
};

struct PathPlot {
  std::string title;
  int width = 1200;                   // px
  int height = 900;                   // px
  std::optional<WorldRect> region;    // m, at least this is shown; absent: every path with a margin
  std::optional<WorldRect> field;     // m, the field inside the walls; its outline is drawn
  int orientation_every = -1;         // frames between heading ticks; 0: none; -1: about every 30 px
  std::string x_label = "x [m]";
  std::string y_label = "y [m]";
  std::vector<PlotPath> paths;
};

struct PlotSeries {
  std::string name;        // legend entry
  std::vector<double> x;   // e.g. s
  std::vector<double> y;   // same length as x
  bool points = false;     // true: a dot at every sample, no line (a scatter)
  // 0xRRGGBB, drawn as a thin solid line (a background such as many measurements in
  // grey); absent: the palette's next colour and style.
  std::optional<std::uint32_t> color = std::nullopt;
  bool legend = true;      // false: no legend entry (the name is ignored)
};

struct SeriesPlot {
  std::string title;
  int width = 1200;   // px
  int height = 700;   // px
  std::string x_label = "t [s]";
  std::string y_label;
  std::optional<WorldRect> range;  // absent: x tight to the data, y with a 5 % margin
  std::vector<PlotSeries> series;
};

// Where everything lands in the image, and the mapping from world to pixels.
struct PlotLayout {
  int width = 0, height = 0;  // px
  Rect plot_area;   // px; data is drawn only in here
  Rect title;       // px, the title's text box (empty without a title)
  Rect x_axis;      // px, below the plot area: ticks, tick labels and the axis label
  Rect y_axis;      // px, left of the plot area: ticks, tick labels and the axis label
  Rect legend;      // px, the legend box (empty without entries)
  bool legend_inside = true;   // false: right of the plot area
  WorldRect view;   // world units of the plot area's edges
  double x_step = 1, y_step = 1;  // world units between ticks

  // The pixel position of a world point (continuous: pixel (i, j) spans [i, i+1] x [j, j+1]).
  Point2d ToPixel(double x, double y) const;
  // The world point at a pixel position.
  void FromPixel(Point2d p, double* x, double* y) const;
};

// The k-th colour of the palette (Okabe-Ito, most contrasting on white first).
Color PlotColor(int k);
// The k-th line style: solid, dashed, dotted, dash-dot, then again, `width` px wide.
LineStyle PlotLineStyle(int k, double width);

// Geometry of a plot. Throws InputError for sizes below 240 x 180 or above 8192 px.
PlotLayout LayoutPathPlot(const PathPlot& plot);
PlotLayout LayoutSeriesPlot(const SeriesPlot& plot);

// Draws a plot; *layout (if given) receives its geometry. Throws what the renderer
// throws (InputError from the null renderer) and what Layout*() throws.
RgbaImage RenderPathPlot(const PathPlot& plot, Renderer& renderer, PlotLayout* layout = nullptr);
RgbaImage RenderSeriesPlot(const SeriesPlot& plot, Renderer& renderer, PlotLayout* layout = nullptr);

// Tick spacing: the smallest 1, 2 or 5 x 10^n that is at least `min_step`.
double NiceStep(double min_step);

}  // namespace twinsim
