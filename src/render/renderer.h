// Drawing 2-D pictures into RGBA images, behind one small interface (Drake's render
// engines): a Renderer draws antialiased polylines (width, colour, dash pattern),
// filled convex polygons and text in pixel coordinates, and hands back an RgbaImage.
//
//   std::unique_ptr<Renderer> r = MakeRenderer("osmesa");
//   r->Begin(640, 480, kWhite);
//   r->DrawPolyline({{10, 10}, {200, 120}}, LineStyle{Color::Hex(0x0072b2), 2.0});
//   r->DrawText("hello", {320, 20}, TextStyle{});
//   RgbaImage image = r->Finish();
//
// Pixel coordinates: x to the right, y down, (0, 0) the top-left corner of the image;
// pixel (i, j) covers [i, i+1] x [j, j+1], so its centre is (i + 0.5, j + 0.5). A 1 px
// line through pixel centres lights exactly one row or column.
//
// Shapes are drawn in call order, each over the ones before. Text is drawn after all
// shapes (FreeType into the finished image), so it is always on top. The same calls
// give the same pixels on the same machine.
//
// Backends: "osmesa" (Mesa's off-screen OpenGL, built when OSMesa is found) and "null"
// (always built: every drawing call throws InputError "rendering not compiled; rebuild
// with -DTWINSIM_WITH_OSMESA=ON").
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "io/png_image.h"

namespace twinsim {

struct Color {
  std::uint8_t r = 0, g = 0, b = 0, a = 255;
  // From 0xRRGGBB, opaque.
  static constexpr Color Hex(std::uint32_t rgb) {
    return Color{static_cast<std::uint8_t>(rgb >> 16), static_cast<std::uint8_t>(rgb >> 8),
                 static_cast<std::uint8_t>(rgb), 255};
  }
  friend bool operator==(const Color&, const Color&) = default;
};

inline constexpr Color kWhite = Color::Hex(0xffffff);
inline constexpr Color kBlack = Color::Hex(0x000000);

struct Point2d {
  double x = 0;  // px
  double y = 0;  // px
};

// An axis-aligned rectangle [x0, x1] x [y0, y1] in pixels.
struct Rect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // px
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool Contains(Point2d p) const { return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1; }
  bool Intersects(const Rect& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  Rect Inflated(double d) const { return Rect{x0 - d, y0 - d, x1 + d, y1 + d}; }
};

enum class LineCap { kButt, kRound };

struct LineStyle {
  Color color;
  double width = 1;           // px
  std::vector<double> dash;   // px along the line: on, off, on, off, ...; empty = solid
  LineCap cap = LineCap::kButt;
};

enum class FontWeight { kRegular, kBold };
enum class HAlign { kLeft, kCenter, kRight };
// kTop/kBottom: the font's ascender/descender line; kMiddle: half the capital height
// above the baseline (centres digits and capitals on the anchor).
enum class VAlign { kTop, kMiddle, kBaseline, kBottom };

struct TextStyle {
  double size = 14;  // px, the em size
  FontWeight weight = FontWeight::kRegular;
  Color color = kBlack;
  HAlign halign = HAlign::kLeft;    // along the text
  VAlign valign = VAlign::kBaseline;  // across the text
  bool vertical = false;            // rotated 90 degrees counter-clockwise (reads upwards)
};

// The box text drawn at `anchor` with `style` occupies: the advance width by the font's
// ascender-to-descender height, rotated when vertical. Needs no renderer. Throws
// InputError when the font files (fonts-dejavu-core) are missing.
Rect MeasureText(const std::string& utf8, Point2d anchor, const TextStyle& style);

// Draws UTF-8 text into `image` (DejaVu Sans through FreeType, light hinting, grey-level
// antialiasing, glyph origins on whole pixels so that small text stays crisp).
void PaintText(RgbaImage* image, const std::string& utf8, Point2d anchor, const TextStyle& style);

class Renderer {
 public:
  virtual ~Renderer() = default;
  virtual std::string name() const = 0;

  // Starts a picture of width x height px filled with `background`; drops any picture
  // under way. Throws InputError for sizes outside 1..8192.
  virtual void Begin(int width, int height, Color background) = 0;
  // Clips what follows to `clip` (whole pixels); ResetClip() draws everywhere again.
  virtual void SetClip(const Rect& clip) = 0;
  virtual void ResetClip() = 0;
  // An antialiased open polyline; non-finite points break it into pieces.
  virtual void DrawPolyline(const std::vector<Point2d>& points, const LineStyle& style) = 0;
  // Separate segments (points 2i, 2i+1) with one style, e.g. ticks or grid lines.
  virtual void DrawSegments(const std::vector<Point2d>& endpoints, const LineStyle& style) = 0;
  // A filled convex polygon with antialiased edges.
  virtual void FillPolygon(const std::vector<Point2d>& points, Color color) = 0;
  // Text, drawn on top of every shape when the picture is finished.
  virtual void DrawText(const std::string& utf8, Point2d anchor, const TextStyle& style) = 0;
  // The finished picture (row 0 at the top).
  virtual RgbaImage Finish() = 0;

  // Conveniences over FillPolygon.
  void FillRect(const Rect& r, Color color);
  void FillCircle(Point2d centre, double radius, Color color);  // radius in px
};

// The message every drawing call of the null renderer throws (as InputError).
inline constexpr const char* kRenderingNotCompiled =
    "rendering not compiled; rebuild with -DTWINSIM_WITH_OSMESA=ON";

// True when this build has a real renderer (OSMesa).
bool RenderingCompiled();
// A renderer by name: "osmesa" or "null". Throws InputError for an unknown name, and
// kRenderingNotCompiled for "osmesa" in a build without it.
std::unique_ptr<Renderer> MakeRenderer(const std::string& name);
// "osmesa" where built, else "null".
std::unique_ptr<Renderer> MakeDefaultRenderer();

}  // namespace twinsim
