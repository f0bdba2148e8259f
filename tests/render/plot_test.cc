// Plots: the world-to-pixel mapping, pixels where the geometry says, a legend and axes
// that never cover data, a readable title, and the same bytes for the same plot.
#include "render/plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "io/png_image.h"
#include "render/pixel_util.h"
#include "render/plot_style.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::ColorDistance;

// A straight path from (x0, y0) to (x1, y1) in `n` poses, heading along it.
PlotPath Line(const std::string& name, double x0, double y0, double x1, double y1, int n = 200) {
  PlotPath p;
  p.name = name;
  for (int i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / (n - 1);
    p.poses.push_back(Pose2{x0 + s * (x1 - x0), y0 + s * (y1 - y0), std::atan2(y1 - y0, x1 - x0)});
  }
  return p;
}

// Distance in colour space (sum of absolute channel differences).

// The smallest ColorDistance in the 3 x 3 pixels around p: p's own pixel may be one a
// line's edge only partly covers.
int NearColorDistance(const RgbaImage& image, Point2d p, Color c) {
  int best = 1000;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int x = static_cast<int>(std::floor(p.x)) + dx, y = static_cast<int>(std::floor(p.y)) + dy;
      if (x >= 0 && y >= 0 && x < image.width && y < image.height) best = std::min(best, ColorDistance(image.at(x, y), c));
    }
  return best;
}

double DistanceToSegment(Point2d p, Point2d a, Point2d b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double s = std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
  return std::hypot(p.x - a.x - s * dx, p.y - a.y - s * dy);
}

TEST(Plot, NiceStepsAreOneTwoFiveTimesAPowerOfTen) {
  EXPECT_DOUBLE_EQ(NiceStep(0.07), 0.1);
  EXPECT_DOUBLE_EQ(NiceStep(0.1), 0.1);
  EXPECT_DOUBLE_EQ(NiceStep(0.11), 0.2);
  EXPECT_DOUBLE_EQ(NiceStep(0.3), 0.5);
  EXPECT_DOUBLE_EQ(NiceStep(3), 5);
  EXPECT_DOUBLE_EQ(NiceStep(6), 10);
  EXPECT_DOUBLE_EQ(NiceStep(1500), 2000);
}

// An axis with one labelled value has no scale: before StepWithTwoTicks, the Robotino's
// turn rate of +-0.42 rad/s on identify's 420 px velocity plot showed "0" alone (70 px
// between ticks asked for just over 0.2, so 0.5, and the view held -0.44 to 0.44). The
// same falls at every decade: amplitudes from 1 to 100 mrad/s.
TEST(Plot, EveryAxisOfASeriesOrPathPlotShowsAtLeastTwoTicks) {
  int checked = 0;
  for (int height : {180, 300, 420, 480}) {
    for (int k = 0; k <= 60; ++k) {
      const double amplitude = 1e-3 * std::pow(10.0, k / 30.0);  // 1 to 100 mrad/s, dense in between
      SeriesPlot plot;
      plot.title = "turn: velocity over the first stretch of the log";
      plot.y_label = "turn velocity [rad/s]";
      plot.x_label = "t [s]";
      plot.height = height;
      PlotSeries s;
      s.name = "measured";
      for (int i = 0; i <= 300; ++i) {
        s.x.push_back(0.5 + i / 32.0);
        s.y.push_back(amplitude * std::sin(i * 0.37));
      }
      plot.series.push_back(s);
      const PlotLayout L = LayoutSeriesPlot(plot);
      EXPECT_GE(plot_style::Ticks(L.view.y_min, L.view.y_max, L.y_step).size(), 2u) << amplitude << " at " << height << " px";
      EXPECT_GE(plot_style::Ticks(L.view.x_min, L.view.x_max, L.x_step).size(), 2u) << amplitude << " at " << height << " px";
      EXPECT_DOUBLE_EQ(NiceStep(L.y_step), L.y_step);  // still 1, 2 or 5 x 10^n
      // The ticks stay readable: 20 px apart; 10 (a 13 px label's digits) on the smallest plot's 54 px axis.
      const double px = L.y_step / (L.view.y_max - L.view.y_min) * L.plot_area.height();
      EXPECT_GE(px, L.plot_area.height() >= 100 ? 20 : 10) << amplitude << " at " << height << " px";
      PathPlot path;
      path.paths.push_back(Line("a", 0, 0, 20 * amplitude, 3 * amplitude));
      path.height = height;
      const PlotLayout P = LayoutPathPlot(path);
      EXPECT_GE(plot_style::Ticks(P.view.y_min, P.view.y_max, P.y_step).size(), 2u) << amplitude << " at " << height << " px";
      EXPECT_GE(plot_style::Ticks(P.view.x_min, P.view.x_max, P.x_step).size(), 2u) << amplitude << " at " << height << " px";
      EXPECT_DOUBLE_EQ(P.x_step, P.y_step);  // equal aspect: one step
      ++checked;
    }
  }
  EXPECT_EQ(checked, 244);
}

TEST(Plot, PaletteAndStylesDiffer) {
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      EXPECT_FALSE(PlotColor(i) == PlotColor(j));
      EXPECT_NE(PlotLineStyle(i, 2).dash, PlotLineStyle(j, 2).dash);
    }
  EXPECT_TRUE(PlotColor(0) == Color::Hex(0x0072b2));  // Okabe-Ito blue
}

TEST(Plot, PathLayoutHasEqualAspectAndShowsTheRegion) {
  PathPlot plot;
  plot.title = "t";
  plot.region = WorldRect{-2, 3, -1, 1};
  plot.paths.push_back(Line("a", -2, -1, 3, 1));
  const PlotLayout L = LayoutPathPlot(plot);
  // 1 m is the same number of pixels along x and y; y grows upwards.
  const Point2d o = L.ToPixel(0, 0), ex = L.ToPixel(1, 0), ey = L.ToPixel(0, 1);
  EXPECT_NEAR(ex.x - o.x, o.y - ey.y, 1e-9);
  EXPECT_GT(ex.x - o.x, 100);
  EXPECT_LE(L.view.x_min, -2);
  EXPECT_GE(L.view.x_max, 3);
  EXPECT_LE(L.view.y_min, -1);
  EXPECT_GE(L.view.y_max, 1);
  double x = 0, y = 0;
  L.FromPixel(L.ToPixel(1.25, -0.5), &x, &y);
  EXPECT_NEAR(x, 1.25, 1e-9);
  EXPECT_NEAR(y, -0.5, 1e-9);
  // Title above, axes left of and below the plot area; everything inside the image.
  EXPECT_LE(L.title.y1, L.plot_area.y0);
  EXPECT_LE(L.y_axis.x1, L.plot_area.x0);
  EXPECT_GE(L.x_axis.y0, L.plot_area.y1);
  for (const Rect& r : {L.plot_area, L.title, L.x_axis, L.y_axis, L.legend}) {
    EXPECT_GE(r.x0, 0);
    EXPECT_GE(r.y0, 0);
    EXPECT_LE(r.x1, plot.width);
    EXPECT_LE(r.y1, plot.height);
  }
  EXPECT_EQ(L.x_step, L.y_step);
}

TEST(Plot, BadRegionOrSizeIsInputError) {
  PathPlot plot;
  plot.region = WorldRect{1, 0, 0, 1};
  EXPECT_THROW(LayoutPathPlot(plot), InputError);
  plot.region.reset();
  plot.width = 100;
  EXPECT_THROW(LayoutPathPlot(plot), InputError);
}

TEST(Plot, KnownSegmentLightsTheExpectedPixelsAndNothingFarFromIt) {
  SKIP_WITHOUT_OSMESA();
  PathPlot plot;
  plot.title = "one segment";
  plot.width = 800;
  plot.height = 600;
  plot.region = WorldRect{0, 10, 0, 10};
  plot.orientation_every = 0;
  plot.paths.push_back(Line("segment", 2, 3, 8, 7));
  auto renderer = MakeRenderer("osmesa");
  PlotLayout L;
  const RgbaImage image = RenderPathPlot(plot, *renderer, &L);
  const Color blue = PlotColor(0);
  const Point2d a = L.ToPixel(2, 3), b = L.ToPixel(8, 7);
  // Along the segment (away from the end markers) the centre pixels are the path's colour.
  for (int k = 1; k < 20; ++k) {
    const double s = 0.05 + 0.9 * k / 20;
    const Point2d p{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y)};
    EXPECT_LE(NearColorDistance(image, p, blue), 20) << s;
  }
  // Every pixel of the path's colour in the plot area (outside the legend's line sample)
  // is near the segment: within the line's half width plus a pixel, or a marker.
  int lit = 0;
  for (int y = static_cast<int>(L.plot_area.y0); y < L.plot_area.y1; ++y) {
    for (int x = static_cast<int>(L.plot_area.x0); x < L.plot_area.x1; ++x) {
      const Point2d c{x + 0.5, y + 0.5};
      if (L.legend.Contains(c)) continue;
      if (ColorDistance(image.at(x, y), blue) > 150) continue;
      ++lit;
      const double d = DistanceToSegment(c, a, b);
      const double to_marker = std::min(std::hypot(c.x - a.x, c.y - a.y), std::hypot(c.x - b.x, c.y - b.y));
      ASSERT_TRUE(d <= 2.0 || to_marker <= 8) << x << "," << y << " is " << d << " px from the segment";
    }
  }
  EXPECT_GT(lit, 0.9 * std::hypot(b.x - a.x, b.y - a.y));
}

TEST(Plot, HeadingTicksPointAlongTheHeading) {
  SKIP_WITHOUT_OSMESA();
  PathPlot plot;
  plot.region = WorldRect{0, 10, 0, 10};
  plot.orientation_every = 1;
  PlotPath p;
  p.name = "turned";
  p.poses = {Pose2{5, 5, kPi / 2}};  // one pose facing +y: a tick straight up in the image
  plot.paths.push_back(p);
  auto renderer = MakeRenderer("osmesa");
  PlotLayout L;
  const RgbaImage image = RenderPathPlot(plot, *renderer, &L);
  const Point2d c = L.ToPixel(5, 5);
  // Above the markers (at most 7.1 px with their white ring), within the tick's 11 px,
  // pixels are tinted with the path's blue; below they are not.
  auto bluish = [&](double y0, double y1) {
    int n = 0;
    for (int y = static_cast<int>(c.y + y0); y <= static_cast<int>(c.y + y1); ++y)
      for (int x = static_cast<int>(c.x) - 2; x <= static_cast<int>(c.x) + 2; ++x)
        n += image.at(x, y)[2] > image.at(x, y)[0] + 60;
    return n;
  };
  EXPECT_GE(bluish(-10.5, -8), 4);
  EXPECT_EQ(bluish(8, 10.5), 0);
}

// Paths that touch every corner of the plot: the legend must go outside.
PathPlot Crowded() {
  PathPlot plot;
  plot.title = "crowded";
  plot.region = WorldRect{0, 4, 0, 3};
  plot.paths.push_back(Line("diagonal", 0, 0, 4, 3));
  plot.paths.push_back(Line("other diagonal", 0, 3, 4, 0));
  plot.paths.push_back(Line("bottom", 0, 0.05, 4, 0.05));
  plot.paths.push_back(Line("top", 0, 2.95, 4, 2.95));
  return plot;
}

TEST(Plot, LegendAndAxesDoNotCoverData) {
  SKIP_WITHOUT_OSMESA();
  auto renderer = MakeRenderer("osmesa");
  PathPlot roomy;
  roomy.title = "roomy";
  roomy.orientation_every = 0;
  roomy.paths.push_back(Line("diagonal", 0, 0, 3, 2));
  roomy.paths.push_back(Line("near it", 0, 0.2, 3, 2.2));
  for (const PathPlot& plot : {roomy, Crowded()}) {
    PlotLayout L;
    const RgbaImage image = RenderPathPlot(plot, *renderer, &L);
    EXPECT_EQ(L.legend_inside, plot.title == "roomy") << plot.title;
    EXPECT_FALSE(L.legend.empty());
    for (const Rect& chrome : {L.x_axis, L.y_axis, L.title}) EXPECT_FALSE(chrome.Intersects(L.plot_area));
    if (!L.legend_inside) {
      EXPECT_FALSE(L.legend.Intersects(L.plot_area));
    }
    for (std::size_t k = 0; k < plot.paths.size(); ++k) {
      const PlotPath& path = plot.paths[k];
      for (std::size_t i = 5; i + 5 < path.poses.size(); i += 3) {
        const Point2d p = L.ToPixel(path.poses[i].x, path.poses[i].y);
        if (!L.plot_area.Contains(p)) continue;
        ASSERT_FALSE(L.legend.Inflated(2).Contains(p)) << plot.title << " path " << k << " pose " << i;
        for (const Rect& chrome : {L.x_axis, L.y_axis, L.title}) ASSERT_FALSE(chrome.Contains(p));
      }
    }
    // The data's pixels really are drawn: on the first path, away from crossings and
    // markers, the centre pixels have its colour.
    const PlotPath& first = plot.paths[0];
    int good = 0, checked = 0;
    for (std::size_t i = 20; i + 20 < first.poses.size(); i += 10) {
      const Point2d p = L.ToPixel(first.poses[i].x, first.poses[i].y);
      if (std::abs(p.x - L.ToPixel(2, 1.5).x) < 20 || !L.plot_area.Inflated(-3).Contains(p)) continue;  // crossing
      ++checked;
      good += NearColorDistance(image, p, PlotColor(0)) <= 20;
    }
    EXPECT_GT(checked, 5);
    EXPECT_EQ(good, checked) << plot.title;
    // The legend holds something: a line sample in each path's colour.
    for (std::size_t k = 0; k < plot.paths.size(); ++k) {
      bool found = false;
      for (int y = static_cast<int>(L.legend.y0); y < L.legend.y1 && !found; ++y)
        for (int x = static_cast<int>(L.legend.x0); x < L.legend.x1 && !found; ++x)
          found = ColorDistance(image.at(x, y), PlotColor(static_cast<int>(k))) < 40;
      EXPECT_TRUE(found) << plot.title << " legend sample " << k;
    }
  }
}

TEST(Plot, TitleTextRenders) {
  SKIP_WITHOUT_OSMESA();
  auto renderer = MakeRenderer("osmesa");
  PathPlot plot = Crowded();
  PlotLayout L;
  const RgbaImage image = RenderPathPlot(plot, *renderer, &L);
  ASSERT_FALSE(L.title.empty());
  EXPECT_LE(L.title.y1, L.plot_area.y0);
  int dark = 0;
  for (int y = static_cast<int>(L.title.y0); y < L.title.y1; ++y)
    for (int x = static_cast<int>(L.title.x0); x < L.title.x1; ++x) dark += ColorDistance(image.at(x, y), kWhite) > 300;
  EXPECT_GT(dark, 60);
  // And nothing of it strays outside its box into the empty band above the plot.
  for (int y = 0; y < L.plot_area.y0 - 2; ++y)
    for (int x = 0; x < image.width; ++x)
      if (!L.title.Inflated(2).Contains(Point2d{x + 0.5, y + 0.5}) && !L.y_axis.Contains(Point2d{x + 0.5, y + 0.5})) {
        ASSERT_EQ(ColorDistance(image.at(x, y), kWhite), 0) << x << "," << y;
      }
}

TEST(Plot, SamePlotGivesSamePngBytes) {
  SKIP_WITHOUT_OSMESA();
  PathPlot plot = Crowded();
  plot.orientation_every = 7;
  auto a = MakeRenderer("osmesa");
  const std::string first = EncodePng(RenderPathPlot(plot, *a));
  EXPECT_EQ(first, EncodePng(RenderPathPlot(plot, *a)));
  auto b = MakeRenderer("osmesa");
  EXPECT_EQ(first, EncodePng(RenderPathPlot(plot, *b)));
}

TEST(Plot, NullRendererFailsWithTheDocumentedMessage) {
  auto null = MakeRenderer("null");
  try {
    RenderPathPlot(Crowded(), *null);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "rendering not compiled; rebuild with -DTWINSIM_WITH_OSMESA=ON");
  }
}

TEST(Plot, SeriesPlotIsTightInTimeAndDrawsItsSeries) {
  SKIP_WITHOUT_OSMESA();
  SeriesPlot plot;
  plot.title = "errors";
  plot.y_label = "error [m]";
  PlotSeries s;
  s.name = "rms";
  for (int i = 0; i <= 100; ++i) {
    s.x.push_back(i * 0.1);
    s.y.push_back(1.0 + 0.5 * std::sin(i * 0.1));
  }
  plot.series.push_back(s);
  auto renderer = MakeRenderer("osmesa");
  PlotLayout L;
  const RgbaImage image = RenderSeriesPlot(plot, *renderer, &L);
  EXPECT_DOUBLE_EQ(L.view.x_min, 0);
  EXPECT_DOUBLE_EQ(L.view.x_max, 10);
  EXPECT_LT(L.view.y_min, 0.5);
  EXPECT_GT(L.view.y_max, 1.5);
  const Point2d p = L.ToPixel(5.0, 1.0 + 0.5 * std::sin(5.0));
  EXPECT_LE(NearColorDistance(image, p, PlotColor(0)), 20);
  EXPECT_FALSE(L.legend.Contains(p));
}

}  // namespace
}  // namespace twinsim
