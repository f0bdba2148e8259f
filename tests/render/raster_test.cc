// Drawing straight into an image: exactly the pixels asked for, in exactly the colour,
// nothing outside the image.
#include "render/raster.h"

#include <gtest/gtest.h>

#include <cstdint>

#include "io/png_image.h"

namespace twinsim {
namespace {

constexpr std::uint32_t kRed = 0xff0000ff;

// The pixel at (x, y) as 0xRRGGBBAA.
std::uint32_t At(const RgbaImage& image, int x, int y) {
  const std::uint8_t* p = image.at(x, y);
  return static_cast<std::uint32_t>(p[0]) << 24 | static_cast<std::uint32_t>(p[1]) << 16 |
         static_cast<std::uint32_t>(p[2]) << 8 | p[3];
}

int CountColour(const RgbaImage& image, std::uint32_t rgba) {
  int n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) n += At(image, x, y) == rgba;
  return n;
}

TEST(Raster, LineLightsOnePixelPerStepAndDashesLeaveRunsOut) {
  RgbaImage image(20, 5, 0xffffffff);
  raster::Line(image, 2, 2, 11, 2, 0, kRed);
  EXPECT_EQ(CountColour(image, kRed), 10);
  for (int x = 2; x <= 11; ++x) EXPECT_EQ(At(image, x, 2), kRed) << x;

  RgbaImage dashed(20, 5, 0xffffffff);
  raster::Line(dashed, 0, 1, 11, 1, 0, kRed, 3);  // steps 0-2 on, 3-5 off, 6-8 on, 9-11 off
  EXPECT_EQ(CountColour(dashed, kRed), 6);
  EXPECT_EQ(At(dashed, 2, 1), kRed);
  EXPECT_EQ(At(dashed, 3, 1), 0xffffffffu);
  EXPECT_EQ(At(dashed, 6, 1), kRed);
}

TEST(Raster, BrushDotAndOutlineCoverTheDocumentedPixels) {
  RgbaImage thick(20, 20, 0xffffffff);
  raster::Line(thick, 5, 10, 14, 10, 1, kRed);  // a 3 px wide brush
  EXPECT_EQ(CountColour(thick, kRed), 12 * 3);  // x 4..15, y 9..11

  RgbaImage dot(9, 9, 0xffffffff);
  raster::Dot(dot, 4, 4, 2, kRed);  // dx^2 + dy^2 <= 6: the 5 x 5 square without its corners
  EXPECT_EQ(CountColour(dot, kRed), 21);
  EXPECT_NE(At(dot, 2, 2), kRed);

  RgbaImage box(10, 8, 0xffffffff);
  raster::Outline(box, 1, 1, 8, 6, kRed);
  EXPECT_EQ(CountColour(box, kRed), 2 * 8 + 2 * 4);
  EXPECT_EQ(At(box, 4, 3), 0xffffffffu);  // inside stays
}

TEST(Raster, NothingIsDrawnOutsideTheImage) {
  RgbaImage image(10, 10, 0xffffffff);
  raster::Ring(image, 0, 0, 30, 2, kRed);  // wholly outside
  raster::Put(image, -1, 3, kRed);
  raster::Put(image, 3, 10, kRed);
  EXPECT_EQ(CountColour(image, kRed), 0);
  raster::Ring(image, 5, 5, 3, 0, kRed);
  EXPECT_GT(CountColour(image, kRed), 8);
  EXPECT_EQ(At(image, 5, 5), 0xffffffffu);  // the centre stays
}

TEST(Raster, PasteCopiesWhatFitsAtItsPlace) {
  RgbaImage into(6, 4, 0xffffffff), from(3, 3, kRed);
  raster::Paste(into, from, 4, 2);  // 2 x 2 of it fit
  EXPECT_EQ(CountColour(into, kRed), 4);
  EXPECT_EQ(At(into, 5, 3), kRed);
  EXPECT_EQ(At(into, 3, 3), 0xffffffffu);
}

TEST(Raster, FadedGreyKeepsTheContrastAskedForOnWhite) {
  RgbaImage image(2, 1, 0x000000ff);
  image.at(1, 0)[3] = 0;  // transparent: white
  const RgbaImage grey = raster::FadedGrey(image, 3, 2, 0.3);
  ASSERT_EQ(grey.width, 3);
  ASSERT_EQ(grey.height, 2);
  EXPECT_EQ(At(grey, 0, 0), 0xb3b3b3ffu);  // black: 255 - 255 * 0.3 = 178.5, rounded up
  EXPECT_EQ(At(grey, 1, 0), 0xffffffffu);
  EXPECT_EQ(At(grey, 2, 1), 0xffffffffu);  // beyond the image: white
  EXPECT_EQ(At(raster::FadedGrey(image, 1, 1, 1.0), 0, 0), 0x000000ffu);
}

}  // namespace
}  // namespace twinsim
