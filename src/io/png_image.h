// RGBA images and their PNG files, through libpng.
//
// Writing is deterministic: the same pixels give the same bytes (fixed compression
// level and filters, no time stamp or other metadata that changes). Reading accepts any
// PNG libpng reads and converts it to 8-bit RGBA.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace twinsim {

struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // height x width x 4, row 0 at the top

  RgbaImage() = default;
  RgbaImage(int w, int h, std::uint32_t rgba = 0xffffffff);
  std::uint8_t* at(int x, int y) { return &pixels[(static_cast<std::size_t>(y) * width + x) * 4]; }
  const std::uint8_t* at(int x, int y) const { return &pixels[(static_cast<std::size_t>(y) * width + x) * 4]; }
};

// The PNG bytes of an image.
std::string EncodePng(const RgbaImage& image);
// Writes an image as PNG atomically; throws InputError when the file cannot be written.
void WritePng(const std::string& path, const RgbaImage& image);
// Reads a PNG; throws InputError "path: ..." when the file is missing or not a PNG.
RgbaImage ReadPng(const std::string& path);

}  // namespace twinsim
