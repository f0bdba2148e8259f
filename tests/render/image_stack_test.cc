#include "render/image_stack.h"

#include <gtest/gtest.h>

namespace twinsim {
namespace {

std::uint32_t Pixel(const RgbaImage& image, int x, int y) {
  const std::uint8_t* p = image.at(x, y);
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

TEST(ImageStack, PutsTheFirstAboveTheSecondAndFillsWithWhite) {
  const RgbaImage top(3, 2, 0xff0000ff), bottom(5, 1, 0x00ff00ff);
  const RgbaImage out = StackImages(top, bottom);
  ASSERT_EQ(out.width, 5);
  ASSERT_EQ(out.height, 3);
  EXPECT_EQ(Pixel(out, 0, 0), 0xff0000ffu);
  EXPECT_EQ(Pixel(out, 2, 1), 0xff0000ffu);
  EXPECT_EQ(Pixel(out, 3, 0), 0xffffffffu);  // beside the narrower top
  EXPECT_EQ(Pixel(out, 4, 1), 0xffffffffu);
  EXPECT_EQ(Pixel(out, 0, 2), 0x00ff00ffu);
  EXPECT_EQ(Pixel(out, 4, 2), 0x00ff00ffu);
}

}  // namespace
}  // namespace twinsim
