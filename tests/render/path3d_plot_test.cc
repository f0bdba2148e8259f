// 3D path plots: the orthographic projection with equal scale on every axis, pixels
// where the projection says, a legend that never covers a path, the same bytes for the
// same plot, and an example picture of the letters "ILC" written in a vertical plane.
#include "render/path3d_plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/png_image.h"
#include "render/pixel_util.h"
#include "render/plot.h"

namespace twinsim {
namespace {

using testing::ColorDistance;

constexpr double kDeg = kPi / 180;

// A straight path from a to b in n points.
Path3D Segment(const std::string& name, const Eigen::Vector3d& a, const Eigen::Vector3d& b, int n = 50) {
  Path3D p;
  p.name = name;
  for (int i = 0; i < n; ++i) p.points.push_back(a + (b - a) * (static_cast<double>(i) / (n - 1)));
  return p;
}

// Sum of absolute channel differences.

double DistanceToRect(Point2d p, const Rect& r) {
  const double dx = std::max({r.x0 - p.x, 0.0, p.x - r.x1}), dy = std::max({r.y0 - p.y, 0.0, p.y - r.y1});
  return std::hypot(dx, dy);
}

// Letters "I", "L", "C" (0.15 m high) written in the x-z plane at y = 0, one point
// every 2 mm; a non-finite point between letters where the pen is lifted.
std::vector<Eigen::Vector3d> Letters() {
  const double z0 = 0.05, z1 = 0.20;
  const std::vector<std::vector<Eigen::Vector3d>> strokes = {
      {{0.00, 0, z1}, {0.00, 0, z0}}, {{0.08, 0, z1}, {0.08, 0, z0}, {0.18, 0, z0}}};
  std::vector<Eigen::Vector3d> out;
  for (const auto& way : strokes) {
    for (std::size_t i = 0; i + 1 < way.size(); ++i) {
      const int n = std::max(1, static_cast<int>(std::ceil((way[i + 1] - way[i]).norm() / 0.002)));
      for (int k = 0; k < n; ++k) out.push_back(way[i] + (way[i + 1] - way[i]) * (static_cast<double>(k) / n));
    }
    out.push_back(way.back());
    out.push_back(Eigen::Vector3d::Constant(NAN));
  }
  const double cx = 0.31, cz = 0.125, r = 0.075;
  for (int k = 0; k <= 200; ++k) {
    const double a = (45 + 270.0 * k / 200) * kDeg;
    out.push_back(Eigen::Vector3d{cx + r * std::cos(a), 0, cz + r * std::sin(a)});
  }
  return out;
}

TEST(Path3DPlot, KnownPointProjectsWhereTheMathSaysAndIsLit) {
  if (!RenderingCompiled()) GTEST_SKIP() << "built without OSMesa";
  Path3DPlot plot;
  plot.title = "projection";
  plot.azimuth_deg = -60;
  plot.elevation_deg = 25;
  plot.show_projection = false;
  const Eigen::Vector3d p{0.3, -0.2, 0.5};
  const Eigen::Vector3d d{0.08, 0.05, -0.06};
  plot.paths.push_back(Segment("through p", p - d, p + d));
  plot.paths.push_back(Segment("frame", {-1, -1, 0}, {1, 1, 1}));
  auto renderer = MakeDefaultRenderer();
  Path3DLayout L;
  const RgbaImage image = RenderPath3DPlot(plot, *renderer, &L);

  // Screen right and up for azimuth a and elevation e (matplotlib's view_init).
  const double a = -60 * kDeg, e = 25 * kDeg;
  const Eigen::Vector3d right{-std::sin(a), std::cos(a), 0};
  const Eigen::Vector3d up{-std::sin(e) * std::cos(a), -std::sin(e) * std::sin(a), std::cos(e)};
  const Point2d o = L.ToPixel(Eigen::Vector3d::Zero()), q = L.ToPixel(p);
  EXPECT_NEAR(q.x, o.x + L.scale * p.dot(right), 1e-9);
  EXPECT_NEAR(q.y, o.y - L.scale * p.dot(up), 1e-9);
  EXPECT_GT(L.scale, 100);
  EXPECT_TRUE(L.box.Contains(q));

  // The pixel under p (or one of its 3 x 3 neighbours, partly covered by a 2 px line)
  // is the first path's blue.
  int best = 1000;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      best = std::min(best, ColorDistance(image.at(static_cast<int>(q.x) + dx, static_cast<int>(q.y) + dy), PlotColor(0)));
  EXPECT_LE(best, 20);
}

TEST(Path3DPlot, EqualScaleOnEveryAxis) {
  for (const auto& [az, el] : {std::pair{-60.0, 25.0}, {30.0, 40.0}, {135.0, 10.0}}) {
    Path3DPlot plot;
    plot.azimuth_deg = az;
    plot.elevation_deg = el;
    plot.paths.push_back(Segment("cube diagonal", {0, 0, 0}, {1, 1, 1}));
    const Path3DLayout L = LayoutPath3DPlot(plot);
    const double a = az * kDeg, e = el * kDeg;
    auto length = [&](const Eigen::Vector3d& edge) {
      const Point2d p0 = L.ToPixel(Eigen::Vector3d::Zero()), p1 = L.ToPixel(edge);
      return std::hypot(p1.x - p0.x, p1.y - p0.y);
    };
    // A unit cube's edges, foreshortened by the view: x by sqrt(sin^2 a + sin^2 e cos^2 a),
    // y by sqrt(cos^2 a + sin^2 e sin^2 a), z by cos e; all with the same px per m.
    const double s = L.scale;
    EXPECT_NEAR(length({1, 0, 0}), s * std::sqrt(std::pow(std::sin(a), 2) + std::pow(std::sin(e) * std::cos(a), 2)), 1e-9);
    EXPECT_NEAR(length({0, 1, 0}), s * std::sqrt(std::pow(std::cos(a), 2) + std::pow(std::sin(e) * std::sin(a), 2)), 1e-9);
    EXPECT_NEAR(length({0, 0, 1}), s * std::cos(e), 1e-9);
    // z is straight up on the screen.
    EXPECT_NEAR(L.ToPixel({0, 0, 1}).x, L.ToPixel({0, 0, 0}).x, 1e-9);
    // The box and everything in the picture fit the image.
    EXPECT_GE(L.box.x0, L.plot_area.x0);
    EXPECT_LE(L.box.x1, L.plot_area.x1);
    EXPECT_GE(L.box.y0, L.plot_area.y0);
    EXPECT_LE(L.box.y1, L.plot_area.y1);
    EXPECT_LE(L.box_min.minCoeff(), 0);
    EXPECT_GE(L.box_max.minCoeff(), 1);
  }
}

TEST(Path3DPlot, BadViewOrSizeIsInputError) {
  Path3DPlot plot;
  plot.elevation_deg = 95;
  EXPECT_THROW(LayoutPath3DPlot(plot), InputError);
  plot.elevation_deg = 25;
  plot.height = 100;
  EXPECT_THROW(LayoutPath3DPlot(plot), InputError);
}

TEST(Path3DPlot, SamePlotGivesSamePngBytes) {
  if (!RenderingCompiled()) GTEST_SKIP() << "built without OSMesa";
  Path3DPlot plot;
  plot.title = "same bytes";
  plot.paths.push_back({"letters", Letters()});
  auto renderer = MakeDefaultRenderer();
  const std::string first = EncodePng(RenderPath3DPlot(plot, *renderer));
  const std::string second = EncodePng(RenderPath3DPlot(plot, *MakeDefaultRenderer()));
  EXPECT_EQ(first, second);
  EXPECT_GT(first.size(), 1000u);
}

TEST(Path3DPlot, LegendCoversNoPath) {
  if (!RenderingCompiled()) GTEST_SKIP() << "built without OSMesa";
  auto renderer = MakeDefaultRenderer();
  Path3DPlot roomy;
  roomy.title = "roomy";
  roomy.paths.push_back({"reference", Letters()});
  Path3DPlot crowded;
  crowded.title = "crowded";
  crowded.paths.push_back(Segment("diagonal", {0, 0, 0}, {1, 1, 1}));
  crowded.paths.push_back(Segment("other diagonal", {1, 0, 1}, {0, 1, 0}));
  crowded.paths.push_back(Segment("third", {0, 1, 1}, {1, 0, 0}));
  crowded.paths.push_back(Segment("fourth", {1, 1, 0}, {0, 0, 1}));
  for (const Path3DPlot& plot : {roomy, crowded}) {
    Path3DLayout L;
    const RgbaImage image = RenderPath3DPlot(plot, *renderer, &L);
    ASSERT_FALSE(L.legend.empty()) << plot.title;
    EXPECT_GE(L.legend.x0, 0);
    EXPECT_LE(L.legend.x1, plot.width);
    // Every projected path point (and its shadow) is farther from the legend than the
    // line's half width, the start and end markers farther than their size.
    for (const auto& path : plot.paths)
      for (std::size_t i = 0; i < path.points.size(); ++i) {
        const Eigen::Vector3d& p = path.points[i];
        if (!p.allFinite()) continue;
        const bool end = i == 0 || i + 1 == path.points.size();
        EXPECT_GT(DistanceToRect(L.ToPixel(p), L.legend), end ? 10 : 1.5) << plot.title << " point " << i;
        EXPECT_GT(DistanceToRect(L.ToPixel({p.x(), p.y(), L.box_min.z()}), L.legend), 1.0) << plot.title;
      }
    // Inside the legend box, only the legend's own line samples have the paths' colours:
    // the rows right of the samples (names) show no colour of a path.
    int coloured = 0;
    for (int y = static_cast<int>(L.legend.y0) + 1; y < L.legend.y1 - 1; ++y)
      for (int x = static_cast<int>(L.legend.x0) + 60; x < L.legend.x1 - 1; ++x)
        for (int k = 0; k < static_cast<int>(plot.paths.size()); ++k)
          coloured += ColorDistance(image.at(x, y), PlotColor(k)) < 60;
    EXPECT_EQ(coloured, 0) << plot.title;
  }
}

TEST(Path3DPlot, NullRendererFailsWithTheDocumentedMessage) {
  Path3DPlot plot;
  plot.paths.push_back({"letters", Letters()});
  auto renderer = MakeRenderer("null");
  try {
    RenderPath3DPlot(plot, *renderer);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(kRenderingNotCompiled), std::string::npos);
  }
}

// The example for issue 4: a reference and a slightly perturbed "tracked" copy of the
// letters, written to /tmp/twinsim_plots/letters3d.png for a look.
TEST(Path3DPlot, LettersExample) {
  if (!RenderingCompiled()) GTEST_SKIP() << "built without OSMesa";
  const std::vector<Eigen::Vector3d> reference = Letters();
  std::vector<Eigen::Vector3d> tracked;
  double along = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    if (i > 0 && reference[i].allFinite() && reference[i - 1].allFinite()) along += (reference[i] - reference[i - 1]).norm();
    // A few millimetres of smooth tracking error, as after some learning trials.
    tracked.push_back(reference[i] + Eigen::Vector3d{0.004 * std::sin(2 * 3.14159 * along / 0.21),
                                                     0.003 * std::sin(2 * 3.14159 * along / 0.37 + 1),
                                                     0.004 * std::cos(2 * 3.14159 * along / 0.16)});
  }
  Path3DPlot plot;
  plot.title = "Writing \u201cILC\u201d: tool path after 10 trials";
  plot.paths.push_back({"reference", reference});
  plot.paths.push_back({"tracked", tracked});
  Path3DLayout L;
  const RgbaImage image = RenderPath3DPlot(plot, *MakeDefaultRenderer(), &L);
  std::filesystem::create_directories("/tmp/twinsim_plots");
  WritePng("/tmp/twinsim_plots/letters3d.png", image);
  EXPECT_TRUE(L.legend_inside);
  EXPECT_EQ(image.width, 1200);
  EXPECT_EQ(image.height, 900);
}

}  // namespace
}  // namespace twinsim
