#include "render/renderer.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>

#include "core/error.h"
#include "core/pose.h"

namespace twinsim {

#ifdef TWINSIM_HAVE_OSMESA
namespace internal {
std::unique_ptr<Renderer> MakeOsMesaRenderer();  // render/osmesa/osmesa_renderer.cc
}  // namespace internal
#endif

namespace {

constexpr const char* kFontDir = "/usr/share/fonts/truetype/dejavu/";
constexpr const char* kFontFiles[] = {"DejaVuSans.ttf", "DejaVuSans-Bold.ttf"};

// Decodes UTF-8; malformed bytes become U+FFFD.
std::vector<char32_t> DecodeUtf8(const std::string& s) {
  std::vector<char32_t> out;
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const int extra = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xe ? 2 : (c >> 3) == 0x1e ? 3 : -1;
    char32_t cp = extra == 0 ? c : extra == 1 ? (c & 0x1f) : extra == 2 ? (c & 0x0f) : (c & 0x07);
    if (extra < 0 || i + extra >= s.size()) {
      out.push_back(0xfffd);
      ++i;
      continue;
    }
    bool ok = true;
    for (int k = 1; k <= extra; ++k) {
      const unsigned char d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xc0) != 0x80) ok = false;
      cp = (cp << 6) | (d & 0x3f);
    }
    out.push_back(ok ? cp : 0xfffd);
    i += ok ? extra + 1 : 1;
  }
  return out;
}

struct Glyph {
  std::vector<std::uint8_t> coverage;  // rows x width, 0..255
  int width = 0, rows = 0;
  int left = 0, top = 0;  // px from the pen position to the bitmap's top-left, y up
  long advance = 0;       // 1/64 px
  unsigned index = 0;     // in the face, for kerning
};

struct FontMetrics {
  int ascender = 0;   // px above the baseline
  int descender = 0;  // px below the baseline (positive)
  int cap_height = 0;  // px
};

// A line of text laid out in its own frame: x along the text from the left end, y down
// from the ascender line; the baseline is at y = ascender.
struct TextRun {
  std::vector<std::pair<const Glyph*, int>> glyphs;  // glyph and its pen x (px)
  int width = 0;   // px, advance width
  FontMetrics metrics;
};

// The process's FreeType library and the two DejaVu faces, loaded on first use, with a
// glyph cache. FreeType faces are not thread-safe, so every use holds the mutex.
class Fonts {
 public:
  static Fonts& Get() {
    static Fonts fonts;
    return fonts;
  }
  std::mutex& mutex() { return mutex_; }

  // Lays out `text`; the glyphs stay valid while the library lives (map nodes are stable).
  TextRun Layout(const std::string& text, const TextStyle& style) {
    Load();
    FT_Face face = faces_[style.weight == FontWeight::kBold ? 1 : 0];
    const long size64 = std::lround(std::clamp(style.size, 4.0, 400.0) * 64);
    SetSize(face, size64);
    TextRun run;
    run.metrics = Metrics(style.weight, face, size64);
    long pen = 0;  // 1/64 px
    unsigned previous = 0;
    for (char32_t cp : DecodeUtf8(text)) {
      const Glyph& g = GlyphFor(style.weight, face, size64, cp);
      if (previous && g.index && FT_HAS_KERNING(face)) {
        FT_Vector delta;
        if (FT_Get_Kerning(face, previous, g.index, FT_KERNING_DEFAULT, &delta) == 0) pen += delta.x;
      }
      run.glyphs.emplace_back(&g, static_cast<int>((pen + 32) >> 6));
      pen += g.advance;
      previous = g.index;
    }
    run.width = static_cast<int>((pen + 32) >> 6);
    return run;
  }

 private:
  Fonts() = default;
  ~Fonts() {
    for (FT_Face f : faces_)
      if (f) FT_Done_Face(f);
    if (library_) FT_Done_FreeType(library_);
  }

  void Load() {
    if (library_) return;
    if (FT_Init_FreeType(&library_)) throw std::runtime_error("FreeType initialisation failed");
    for (int i = 0; i < 2; ++i) {
      const std::string path = std::string(kFontDir) + kFontFiles[i];
      if (FT_New_Face(library_, path.c_str(), 0, &faces_[i])) {
        faces_[i] = nullptr;
        throw InputError(SourceLocation{path}, "cannot load font (install the Debian package fonts-dejavu-core)");
      }
    }
  }

  void SetSize(FT_Face face, long size64) {
    if (face->size && face->size->metrics.x_ppem && current_size_[face] == size64) return;
    FT_Set_Char_Size(face, 0, size64, 72, 72);
    current_size_[face] = size64;
  }

  FontMetrics Metrics(FontWeight weight, FT_Face face, long size64) {
    auto key = std::make_pair(static_cast<int>(weight), size64);
    auto it = metrics_.find(key);
    if (it != metrics_.end()) return it->second;
    FontMetrics m;
    m.ascender = static_cast<int>((face->size->metrics.ascender + 63) >> 6);
    m.descender = static_cast<int>((-face->size->metrics.descender + 63) >> 6);
    m.cap_height = GlyphFor(weight, face, size64, U'H').top;
    metrics_[key] = m;
    return m;
  }

  const Glyph& GlyphFor(FontWeight weight, FT_Face face, long size64, char32_t cp) {
    auto key = std::make_tuple(static_cast<int>(weight), size64, cp);
    auto it = glyphs_.find(key);
    if (it != glyphs_.end()) return it->second;
    Glyph g;
    g.index = FT_Get_Char_Index(face, cp);
    // Light hinting snaps only vertically: crisp stems and baselines, true shapes.
    if (FT_Load_Glyph(face, g.index, FT_LOAD_TARGET_LIGHT | FT_LOAD_RENDER) == 0) {
      const FT_GlyphSlot slot = face->glyph;
      const FT_Bitmap& bm = slot->bitmap;
      g.advance = slot->advance.x;
      g.left = slot->bitmap_left;
      g.top = slot->bitmap_top;
      if (bm.pixel_mode == FT_PIXEL_MODE_GRAY) {
        g.width = static_cast<int>(bm.width);
        g.rows = static_cast<int>(bm.rows);
        g.coverage.resize(static_cast<std::size_t>(g.width) * g.rows);
        for (int y = 0; y < g.rows; ++y)
          std::copy_n(bm.buffer + static_cast<std::ptrdiff_t>(y) * bm.pitch, g.width,
                      g.coverage.begin() + static_cast<std::ptrdiff_t>(y) * g.width);
      }
    }
    return glyphs_.emplace(key, std::move(g)).first->second;
  }

  std::mutex mutex_;
  FT_Library library_ = nullptr;
  FT_Face faces_[2] = {nullptr, nullptr};
  std::map<FT_Face, long> current_size_;
  std::map<std::pair<int, long>, FontMetrics> metrics_;
  std::map<std::tuple<int, long, char32_t>, Glyph> glyphs_;
};

// Where the text frame's origin (the top-left of the line box) lands on the image, in
// whole pixels, and the box the text occupies.
struct Placement {
  int ox = 0, oy = 0;
  Rect box;
};

Placement Place(const TextRun& run, Point2d anchor, const TextStyle& style) {
  const int height = run.metrics.ascender + run.metrics.descender;
  const double along = style.halign == HAlign::kLeft ? 0 : style.halign == HAlign::kCenter ? run.width / 2.0 : run.width;
  double across = 0;
  switch (style.valign) {
    case VAlign::kTop: across = 0; break;
    case VAlign::kMiddle: across = run.metrics.ascender - run.metrics.cap_height / 2.0; break;
    case VAlign::kBaseline: across = run.metrics.ascender; break;
    case VAlign::kBottom: across = height; break;
  }
  Placement p;
  if (!style.vertical) {
    p.ox = static_cast<int>(std::lround(anchor.x - along));
    p.oy = static_cast<int>(std::lround(anchor.y - across));
    p.box = Rect{double(p.ox), double(p.oy), double(p.ox + run.width), double(p.oy + height)};
  } else {
    // Text frame (tx, ty) -> image (ox + ty, oy - tx): reads upwards, its top to the left.
    p.ox = static_cast<int>(std::lround(anchor.x - across));
    p.oy = static_cast<int>(std::lround(anchor.y + along));
    p.box = Rect{double(p.ox), double(p.oy - run.width), double(p.ox + height), double(p.oy)};
  }
  return p;
}

void Blend(RgbaImage* image, int x, int y, Color color, int coverage) {
  if (x < 0 || y < 0 || x >= image->width || y >= image->height || coverage <= 0) return;
  const int a = coverage * color.a;  // 0 .. 255 * 255
  std::uint8_t* px = image->at(x, y);
  const std::uint8_t src[3] = {color.r, color.g, color.b};
  for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>((px[c] * (65025 - a) + src[c] * a + 32512) / 65025);
  px[3] = static_cast<std::uint8_t>((px[3] * (65025 - a) + 255 * a + 32512) / 65025);
}

// The null renderer: every drawing call says that rendering was not built.
class NullRenderer : public Renderer {
 public:
  std::string name() const override { return "null"; }
  void Begin(int, int, Color) override { Fail(); }
  void SetClip(const Rect&) override { Fail(); }
  void ResetClip() override { Fail(); }
  void DrawPolyline(const std::vector<Point2d>&, const LineStyle&) override { Fail(); }
  void DrawSegments(const std::vector<Point2d>&, const LineStyle&) override { Fail(); }
  void FillPolygon(const std::vector<Point2d>&, Color) override { Fail(); }
  void DrawText(const std::string&, Point2d, const TextStyle&) override { Fail(); }
  RgbaImage Finish() override { Fail(); }

 private:
  [[noreturn]] static void Fail() { throw InputError(kRenderingNotCompiled); }
};

}  // namespace

Rect MeasureText(const std::string& utf8, Point2d anchor, const TextStyle& style) {
  Fonts& fonts = Fonts::Get();
  std::lock_guard<std::mutex> lock(fonts.mutex());
  return Place(fonts.Layout(utf8, style), anchor, style).box;
}

void PaintText(RgbaImage* image, const std::string& utf8, Point2d anchor, const TextStyle& style) {
  Fonts& fonts = Fonts::Get();
  std::lock_guard<std::mutex> lock(fonts.mutex());
  const TextRun run = fonts.Layout(utf8, style);
  const Placement p = Place(run, anchor, style);
  for (const auto& [g, pen] : run.glyphs) {
    // The glyph's top-left in the text frame.
    const int gx = pen + g->left, gy = run.metrics.ascender - g->top;
    for (int r = 0; r < g->rows; ++r) {
      for (int c = 0; c < g->width; ++c) {
        const int cov = g->coverage[static_cast<std::size_t>(r) * g->width + c];
        if (!cov) continue;
        const int tx = gx + c, ty = gy + r;
        if (!style.vertical)
          Blend(image, p.ox + tx, p.oy + ty, style.color, cov);
        else
          Blend(image, p.ox + ty, p.oy - tx - 1, style.color, cov);
      }
    }
  }
}

void Renderer::FillRect(const Rect& r, Color color) {
  FillPolygon({{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}}, color);
}

void Renderer::FillCircle(Point2d centre, double radius, Color color) {
  // Enough sides that the polygon strays less than a tenth of a pixel from the circle.
  const int n = std::clamp(static_cast<int>(std::ceil(kPi * std::sqrt(std::max(radius, 0.0) / 0.2))), 12, 256);
  std::vector<Point2d> pts(n);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    pts[i] = Point2d{centre.x + radius * std::cos(a), centre.y + radius * std::sin(a)};
  }
  FillPolygon(pts, color);
}

bool RenderingCompiled() {
#ifdef TWINSIM_HAVE_OSMESA
  return true;
#else
  return false;
#endif
}

std::unique_ptr<Renderer> MakeRenderer(const std::string& name) {
  if (name == "null") return std::make_unique<NullRenderer>();
  if (name == "osmesa") {
#ifdef TWINSIM_HAVE_OSMESA
    return internal::MakeOsMesaRenderer();
#else
    throw InputError(kRenderingNotCompiled);
#endif
  }
  throw InputError("unknown renderer '" + name + "' (known: osmesa, null)");
}

std::unique_ptr<Renderer> MakeDefaultRenderer() { return MakeRenderer(RenderingCompiled() ? "osmesa" : "null"); }

}  // namespace twinsim
