// The look every twinsim plot shares (path, time-series and 3D plots): spacing in
// pixels tuned on 1200 x 900 pictures, colours, text styles, and tick labels.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace twinsim::plot_style {

inline constexpr double kOuterPad = 18;       // around everything
inline constexpr double kTickLength = 5;      // outward from the frame or box edge
inline constexpr double kTickGap = 4;         // tick to tick label
inline constexpr double kLabelGap = 9;        // tick labels to axis label
inline constexpr double kTitleGap = 14;       // title to plot area
inline constexpr double kLegendInset = 10;    // legend to the plot area's edges
inline constexpr double kLegendGap = 16;      // plot area to a legend outside on the right
inline constexpr double kLegendPad = 10;      // inside the legend box
inline constexpr double kLegendRow = 22;      // height of a legend row
inline constexpr double kLegendSample = 36;   // length of a legend's line sample
inline constexpr double kDataWidth = 2.0;     // data lines
inline constexpr double kMarkerRadius = 5.5;  // start circle; the end square has the same area
inline constexpr double kMarkerRing = 1.6;    // white ring around markers
inline constexpr double kMarkerStep = 3.6;    // larger radius per later marker at the same place
inline constexpr double kDotRadius = 3.0;     // a scatter series' dots

inline constexpr Color kTitleColor = Color::Hex(0x111111);
inline constexpr Color kLabelColor = Color::Hex(0x222222);
inline constexpr Color kTickLabelColor = Color::Hex(0x333333);
inline constexpr Color kGridColor = Color::Hex(0xe6e6e6);
inline constexpr Color kLegendBorder = Color::Hex(0xcccccc);
inline constexpr Color kMarkerKeyColor = Color::Hex(0x555555);

inline TextStyle TitleStyle() { return TextStyle{19, FontWeight::kBold, kTitleColor, HAlign::kCenter, VAlign::kTop}; }
inline TextStyle LabelStyle(VAlign v = VAlign::kTop) {
  return TextStyle{15, FontWeight::kRegular, kLabelColor, HAlign::kCenter, v};
}
inline TextStyle TickStyle(VAlign v = VAlign::kTop) {
  return TextStyle{13, FontWeight::kRegular, kTickLabelColor, HAlign::kCenter, v};
}
inline TextStyle LegendStyle() { return TextStyle{14, FontWeight::kRegular, kLabelColor, HAlign::kLeft, VAlign::kMiddle}; }

// Start (circle) and end (square of the same area) markers of paths k = 0, 1, ... in
// PlotColor(k), ringed in white; where paths start or end at the same place, earlier
// paths' markers are larger, so that each shows as a ring around the later ones.
void DrawStartEndMarkers(Renderer& r, const std::vector<std::optional<Point2d>>& starts,
                         const std::vector<std::optional<Point2d>>& ends);

// A tick label for v on a grid of `step`: as many decimals as the step needs, a true
// minus sign, "0" for zero.
std::string FormatTick(double v, double step);
// The multiples of `step` within [lo, hi] (at most 1000).
std::vector<double> Ticks(double lo, double hi, double step);

}  // namespace twinsim::plot_style
