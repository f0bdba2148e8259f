#include "io/png_image.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(PngImage, RoundTripKeepsEveryPixel) {
  RgbaImage image(7, 5, 0x102030ff);
  image.at(3, 2)[0] = 255;
  image.at(6, 4)[3] = 7;
  const std::string path = testing::TempDir("png") + "/a.png";
  WritePng(path, image);
  const RgbaImage back = ReadPng(path);
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 5);
  EXPECT_EQ(back.pixels, image.pixels);
}

TEST(PngImage, SamePixelsGiveTheSameBytes) {
  RgbaImage image(64, 48, 0xffffffff);
  for (int x = 0; x < 64; ++x) image.at(x, x % 48)[1] = 0;
  EXPECT_EQ(EncodePng(image), EncodePng(image));
  EXPECT_EQ(EncodePng(image).substr(1, 3), "PNG");
}

TEST(PngImage, NotAPngIsAnInputError) {
  const std::string path = testing::WriteText(testing::TempDir("png_bad") + "/x.png", "hello");
  try {
    ReadPng(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot read PNG"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twinsim
