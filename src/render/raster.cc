#include "render/raster.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/math_constants.h"

namespace twinsim::raster {

void Put(RgbaImage& image, int x, int y, std::uint32_t rgba) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  std::uint8_t* p = image.at(x, y);
  p[0] = static_cast<std::uint8_t>(rgba >> 24);
  p[1] = static_cast<std::uint8_t>(rgba >> 16);
  p[2] = static_cast<std::uint8_t>(rgba >> 8);
  p[3] = static_cast<std::uint8_t>(rgba);
}

void Dot(RgbaImage& image, int x, int y, int radius, std::uint32_t rgba) {
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx)
      if (dx * dx + dy * dy <= radius * radius + radius) Put(image, x + dx, y + dy, rgba);
}

void Line(RgbaImage& image, double x0, double y0, double x1, double y1, int radius, std::uint32_t rgba, int dash) {
  const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))));
  for (int i = 0; i <= steps; ++i) {
    if (dash > 0 && (i / dash) % 2 == 1) continue;
    const double s = static_cast<double>(i) / steps;
    const int x = static_cast<int>(std::lround(x0 + s * (x1 - x0)));
    const int y = static_cast<int>(std::lround(y0 + s * (y1 - y0)));
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) Put(image, x + dx, y + dy, rgba);
  }
}

void Ring(RgbaImage& image, double cx, double cy, double r, int radius, std::uint32_t rgba) {
  const int n = std::max(16, static_cast<int>(2 * kPi * r));
  for (int i = 0; i < n; ++i) {
    const double a0 = 2 * kPi * i / n, a1 = 2 * kPi * (i + 1) / n;
    Line(image, cx + r * std::cos(a0), cy + r * std::sin(a0), cx + r * std::cos(a1), cy + r * std::sin(a1), radius,
         rgba);
  }
}

void Outline(RgbaImage& image, int x0, int y0, int x1, int y1, std::uint32_t rgba) {
  Line(image, x0, y0, x1, y0, 0, rgba);
  Line(image, x1, y0, x1, y1, 0, rgba);
  Line(image, x1, y1, x0, y1, 0, rgba);
  Line(image, x0, y1, x0, y0, 0, rgba);
}

void Paste(RgbaImage& into, const RgbaImage& from, int left, int top) {
  for (int y = 0; y < from.height; ++y)
    for (int x = 0; x < from.width; ++x)
      if (left + x < into.width && top + y < into.height)
        std::copy(from.at(x, y), from.at(x, y) + 4, into.at(left + x, top + y));
}

RgbaImage FadedGrey(const RgbaImage& image, int width, int height, double contrast) {
  static const std::uint8_t kWhitePixel[4] = {255, 255, 255, 255};
  RgbaImage out(width, height, 0xffffffff);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* c = x < image.width && y < image.height ? image.at(x, y) : kWhitePixel;
      const double alpha = c[3] / 255.0;
      const double lum = alpha * (0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]) + (1 - alpha) * 255;
      const auto grey = static_cast<std::uint8_t>(std::lround(255 - (255 - lum) * contrast));
      std::uint8_t* p = out.at(x, y);
      p[0] = p[1] = p[2] = grey;
      p[3] = 255;
    }
  return out;
}

}  // namespace twinsim::raster
