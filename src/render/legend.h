// The legend every twinsim plot shares (path, time-series and 3D plots): a box of rows,
// each a line sample (or a dot) and a name, or the key to the start and end markers.
// It goes into the corner of the plot area with no data under it, or, when every corner
// has some, outside on the right.
//
//   Occupancy data(plot_area);
//   data.MarkSegment(a, b, kDataWidth);  // every piece of data, in pixels
//   const LegendSize size = MeasureLegend(entries);
//   std::optional<Rect> box = LegendCorner(plot_area, size, data);
//   if (!box) ...lay the plot out again with LegendRight(plot_area, size)...
//   DrawLegend(renderer, entries, *box);
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace twinsim::plot_style {

enum class LegendMarker {
  kLine,      // a line sample in the entry's style
  kDot,       // a dot in the entry's colour (a scatter series)
  kStartEnd,  // the key to the start and end markers (circle "start", square "end"); no name
};

struct LegendEntry {
  std::string name;
  LineStyle line;
  LegendMarker marker = LegendMarker::kLine;
};

struct LegendSize {
  double width = 0, height = 0;  // px
};

// Which 4 px cells of a plot area hold something, so that a legend can avoid them.
class Occupancy {
 public:
  explicit Occupancy(const Rect& area);
  // Marks every cell the rectangle touches.
  void MarkRect(const Rect& r);
  // Marks the cells within r px of p (a square); non-finite points mark nothing.
  void MarkDisc(Point2d p, double r);
  // Marks the cells within r px of the segment from a to b; segments with a non-finite
  // end, or wholly outside the area, mark nothing.
  void MarkSegment(Point2d a, Point2d b, double r);
  // The marked cells the rectangle touches.
  int Count(const Rect& r) const;

 private:
  static constexpr double kCell = 4;  // px
  static int Cell(double v) { return static_cast<int>(std::floor(v / kCell)); }
  Rect area_;
  int nx_ = 1, ny_ = 1;
  std::vector<std::uint8_t> cells_;
};

// The size of the legend box for `entries` (0 x 0 when there are none).
LegendSize MeasureLegend(const std::vector<LegendEntry>& entries);

// The legend's box in a corner of `area`, kLegendInset from its edges: of the corners
// where it fits (top right, top left, bottom right, bottom left, preferred in that
// order), the one with the fewest `data` cells under it, then the fewest `decoration`
// cells (if given). Empty when no corner fits or each has data under it.
std::optional<Rect> LegendCorner(const Rect& area, LegendSize size, const Occupancy& data,
                                 const Occupancy* decoration = nullptr);

// The legend's box outside `area`, kLegendGap right of it, level with its top.
Rect LegendRight(const Rect& area, LegendSize size);

// Draws the legend box with `entries` in it (nothing when there are none).
void DrawLegend(Renderer& r, const std::vector<LegendEntry>& entries, const Rect& box);

}  // namespace twinsim::plot_style
