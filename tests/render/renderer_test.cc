// The renderer: pixels land where the geometry says, antialiased but nothing stray,
// text renders, the same calls give the same bytes, and the null renderer says it is one.
#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/error.h"
#include "io/png_image.h"
#include "test_util.h"

namespace twinsim {
namespace {

// Grey level of a pixel (0 black .. 255 white) on a white background drawn in black.
int Grey(const RgbaImage& image, int x, int y) {
  const std::uint8_t* p = image.at(x, y);
  return (p[0] + p[1] + p[2]) / 3;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Renderer, NullRendererSaysRenderingIsNotCompiled) {
  auto null = MakeRenderer("null");
  EXPECT_EQ(null->name(), "null");
  EXPECT_EQ(ErrorOf([&] { null->Begin(100, 100, kWhite); }),
            "rendering not compiled; rebuild with -DTWINSIM_WITH_OSMESA=ON");
  EXPECT_EQ(ErrorOf([&] { null->Finish(); }), kRenderingNotCompiled);
  EXPECT_EQ(ErrorOf([] { MakeRenderer("vulkan"); }), "unknown renderer 'vulkan' (known: osmesa, null)");
  if (!RenderingCompiled()) {
    EXPECT_EQ(ErrorOf([] { MakeRenderer("osmesa"); }), kRenderingNotCompiled);
    EXPECT_EQ(MakeDefaultRenderer()->name(), "null");
  } else {
    EXPECT_EQ(MakeDefaultRenderer()->name(), "osmesa");
  }
}

TEST(Renderer, HorizontalLineLightsExactlyItsRows) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  r->Begin(200, 100, kWhite);
  // 3 px wide, centred on y = 50.5: rows 49, 50 and 51, columns 20 to 179.
  r->DrawPolyline({{20, 50.5}, {180, 50.5}}, LineStyle{kBlack, 3.0, {}, LineCap::kButt});
  const RgbaImage image = r->Finish();
  ASSERT_EQ(image.width, 200);
  ASSERT_EQ(image.height, 100);
  for (int x = 21; x < 179; ++x) {
    for (int y = 49; y <= 51; ++y) EXPECT_LE(Grey(image, x, y), 2) << x << "," << y;
    EXPECT_GE(Grey(image, x, 48), 253) << x;
    EXPECT_GE(Grey(image, x, 52), 253) << x;
  }
  // Butt ends: half a pixel of feather either side of x = 20 and x = 180.
  EXPECT_GE(Grey(image, 18, 50), 253);
  EXPECT_LE(Grey(image, 20, 50), 2);
  EXPECT_LE(Grey(image, 179, 50), 2);
  EXPECT_GE(Grey(image, 181, 50), 253);
  // Nothing farther than 2 px from the segment is touched.
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 200; ++x)
      if (y < 47 || y > 53 || x < 17 || x > 182) {
        ASSERT_EQ(Grey(image, x, y), 255) << x << "," << y;
      }
}

TEST(Renderer, DiagonalLineIsDarkOnItsAxisAndAntialiasedWithinAPixel) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  r->Begin(120, 120, kWhite);
  r->DrawPolyline({{10, 20}, {100, 110}}, LineStyle{kBlack, 2.0, {}, LineCap::kButt});
  const RgbaImage image = r->Finish();
  int grey_levels = 0;
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 120; ++x) {
      const double cx = x + 0.5, cy = y + 0.5;
      // Distance from the pixel centre to the line y = x + 10, within the segment's span.
      const double d = std::abs(cy - cx - 10) / std::sqrt(2.0);
      const bool inside_span = cx > 12 && cx < 98;
      const int g = Grey(image, x, y);
      if (inside_span && d < 0.3) {
        EXPECT_LE(g, 40) << x << "," << y;
      }
      if (d > 2.1) {
        ASSERT_EQ(g, 255) << x << "," << y;
      }
      if (g > 20 && g < 235) ++grey_levels;
    }
  }
  EXPECT_GT(grey_levels, 100);  // edges are antialiased, not staircased
}

TEST(Renderer, DashesAlternateAlongTheLine) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  r->Begin(220, 40, kWhite);
  r->DrawPolyline({{10, 20.5}, {210, 20.5}}, LineStyle{kBlack, 2.0, {10, 10}, LineCap::kButt});
  const RgbaImage image = r->Finish();
  // On 10..20, off 20..30, on 30..40, ...
  for (int k = 0; k < 10; ++k) {
    EXPECT_LE(Grey(image, 15 + 20 * k, 20), 10) << k;
    EXPECT_GE(Grey(image, 25 + 20 * k, 20), 245) << k;
  }
}

TEST(Renderer, PolygonsOnPixelEdgesAreCrispAndClipHolds) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  r->Begin(60, 40, kWhite);
  r->FillRect(Rect{10, 10, 30, 20}, Color::Hex(0xd55e00));
  r->SetClip(Rect{0, 0, 40, 40});
  r->DrawPolyline({{0, 30.5}, {60, 30.5}}, LineStyle{kBlack, 1.0, {}, LineCap::kButt});
  r->ResetClip();
  const RgbaImage image = r->Finish();
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 60; ++x) {
      const std::uint8_t* p = image.at(x, y);
      if (x >= 10 && x < 30 && y >= 10 && y < 20) {
        EXPECT_EQ(p[0], 0xd5) << x << "," << y;
        EXPECT_EQ(p[1], 0x5e);
        EXPECT_EQ(p[2], 0x00);
      } else if (y == 30 && x < 40) {
        EXPECT_EQ(Grey(image, x, y), 0) << x;
      } else {
        EXPECT_EQ(Grey(image, x, y), 255) << x << "," << y;
      }
      EXPECT_EQ(p[3], 255);
    }
  }
}

TEST(Renderer, TextRendersInsideItsMeasuredBox) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  r->Begin(300, 120, kWhite);
  TextStyle style{14, FontWeight::kRegular, kBlack, HAlign::kCenter, VAlign::kMiddle};
  const Rect box = MeasureText("x [m] \u2212 0.5", {150, 40}, style);
  EXPECT_NEAR((box.x0 + box.x1) / 2, 150, 1);
  EXPECT_GT(box.width(), 50);
  EXPECT_GE(box.height(), 14);
  r->DrawText("x [m] \u2212 0.5", {150, 40}, style);
  TextStyle vertical = style;
  vertical.vertical = true;
  const Rect vbox = MeasureText("y [m]", {30, 80}, vertical);
  EXPECT_GT(vbox.height(), vbox.width());
  r->DrawText("y [m]", {30, 80}, vertical);
  const RgbaImage image = r->Finish();
  int inked = 0, dark = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const int g = Grey(image, x, y);
      if (g == 255) continue;
      const Point2d p{x + 0.5, y + 0.5};
      ASSERT_TRUE(box.Inflated(2).Contains(p) || vbox.Inflated(2).Contains(p)) << x << "," << y;
      ++inked;
      if (g < 64) ++dark;
    }
  }
  EXPECT_GT(inked, 150);
  EXPECT_GT(dark, 40);  // crisp: many glyph pixels are fully dark, not a grey smear
}

TEST(Renderer, SameCallsGiveSameBytes) {
  SKIP_WITHOUT_OSMESA();
  auto draw = [](Renderer& r) {
    r.Begin(160, 90, Color::Hex(0xfafafa));
    r.DrawPolyline({{5, 5}, {80, 70}, {150, 10}, {155, 85}}, LineStyle{Color::Hex(0x009e73), 2.5, {6, 4}, LineCap::kRound});
    r.FillCircle({40, 40}, 7.3, Color{204, 121, 167, 200});
    r.DrawText("same", {80, 45}, TextStyle{});
    return EncodePng(r.Finish());
  };
  auto a = MakeRenderer("osmesa");
  auto b = MakeRenderer("osmesa");
  const std::string first = draw(*a);
  EXPECT_EQ(first, draw(*a));
  EXPECT_EQ(first, draw(*b));
}

TEST(Renderer, RejectsSillySizes) {
  SKIP_WITHOUT_OSMESA();
  auto r = MakeRenderer("osmesa");
  EXPECT_NE(ErrorOf([&] { r->Begin(0, 10, kWhite); }).find("outside 1..8192"), std::string::npos);
}

}  // namespace
}  // namespace twinsim
