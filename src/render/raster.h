// Drawing straight into an RgbaImage, pixel by pixel: no antialiasing, no renderer, so
// every pixel is exactly the colour asked for (pictures meant to be read pixel by pixel,
// such as `twinsim regress`'s highlights). For plots, use a Renderer (renderer.h).
//
// Colours are 0xRRGGBBAA, as RgbaImage's constructor takes them; pixels outside the
// image are left out silently.
//
//   RgbaImage image(200, 100, 0xffffffff);
//   raster::Line(image, 10, 10, 190, 90, 1, 0x0072b2ff);
//   raster::Outline(image, 0, 0, 199, 99, 0xccccccff);
#pragma once

#include <cstdint>

#include "io/png_image.h"

namespace twinsim::raster {

// Sets pixel (x, y) to `rgba`.
void Put(RgbaImage& image, int x, int y, std::uint32_t rgba);

// A filled disc of `radius` px around pixel (x, y).
void Dot(RgbaImage& image, int x, int y, int radius, std::uint32_t rgba);

// A line from (x0, y0) to (x1, y1) px drawn with a square brush of `radius` px (0: one
// pixel wide); with dash > 0, every other run of `dash` steps is left out.
void Line(RgbaImage& image, double x0, double y0, double x1, double y1, int radius, std::uint32_t rgba, int dash = 0);

// A circle of radius r px around (cx, cy), drawn as short lines with a brush of `radius`.
void Ring(RgbaImage& image, double cx, double cy, double r, int radius, std::uint32_t rgba);

// The one-pixel outline of the rectangle with corners (x0, y0) and (x1, y1), both drawn.
void Outline(RgbaImage& image, int x0, int y0, int x1, int y1, std::uint32_t rgba);

// Copies `from` into `into` with its top-left corner at (left, top); what falls right of
// or below `into` is left out.
void Paste(RgbaImage& into, const RgbaImage& from, int left, int top);

// `image` as grey levels faded towards white, on a white canvas of width x height px:
// each pixel's luminance (over white, by its alpha) keeps `contrast` of its distance
// from white (1: plain luminance, 0: white).
RgbaImage FadedGrey(const RgbaImage& image, int width, int height, double contrast);

}  // namespace twinsim::raster
