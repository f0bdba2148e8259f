// The OSMesa renderer: Mesa's off-screen OpenGL (llvmpipe) draws the shapes into a
// client buffer; FreeType draws the text into the finished image.
//
// Antialiasing without multisampling (OSMesa has none): every shape is tessellated into
// triangles with a one-pixel feather, the colour's alpha falling from full inside to zero
// one pixel further out, which approximates each pixel's coverage. Where a shape's own
// pieces overlap (joints of a polyline, round caps, dashes), the feathers must not add up
// into dark beads: each draw call gets its own depth layer, later calls in front of earlier
// ones, and inside a layer the depth grows as the alpha falls, so with GL_LESS a fragment
// only lands where its own call has not yet put a more opaque one there.
#include <GL/osmesa.h>
#include <GL/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"
#include "render/renderer.h"

namespace twinsim {
namespace internal {
namespace {

constexpr int kLayers = 4096;                  // depth layers before the depth buffer is cleared
constexpr double kLayerSpan = 1.0 / kLayers;   // of the [0, 1] depth range
constexpr double kSimplifyTolerance = 0.2;     // px: polylines may move this far when thinned
constexpr double kSharpTurn = 0.0;             // cos of the turn (90 deg) beyond which joints are round
constexpr std::size_t kFlushVertices = 1 << 20;

// GL_C4UB_V3F: four colour bytes, then x, y, z.
struct Vertex {
  std::uint8_t r, g, b, a;
  float x, y, z;
};
static_assert(sizeof(Vertex) == 16);

struct Vec {
  double x = 0, y = 0;
};
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y}; }
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y}; }
Vec operator*(Vec a, double s) { return {a.x * s, a.y * s}; }
double Dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y; }
double Length(Vec a) { return std::hypot(a.x, a.y); }
Vec Normalized(Vec a) {
  const double l = Length(a);
  return l > 0 ? a * (1 / l) : Vec{1, 0};
}
Vec Normal(Vec d) { return {-d.y, d.x}; }

// Douglas-Peucker thinning: drops points that lie within `tolerance` of the line through
// their kept neighbours. Paths of thousands of samples shrink to what a pixel grid shows.
std::vector<Vec> Simplify(const std::vector<Vec>& in, double tolerance) {
  std::vector<Vec> pts;
  pts.reserve(in.size());
  for (const Vec& p : in)
    if (pts.empty() || Length(p - pts.back()) > 1e-3) pts.push_back(p);
  if (pts.size() < 3) return pts;
  std::vector<char> keep(pts.size(), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, pts.size() - 1}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (b <= a + 1) continue;
    const Vec ab = pts[b] - pts[a];
    const double len = Length(ab);
    double worst = -1;
    std::size_t worst_i = a;
    for (std::size_t i = a + 1; i < b; ++i) {
      const Vec ap = pts[i] - pts[a];
      const double d = len > 1e-9 ? std::abs(ab.x * ap.y - ab.y * ap.x) / len : Length(ap);
      if (d > worst) {
        worst = d;
        worst_i = i;
      }
    }
    if (worst > tolerance) {
      keep[worst_i] = 1;
      stack.push_back({a, worst_i});
      stack.push_back({worst_i, b});
    }
  }
  std::vector<Vec> out;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (keep[i]) out.push_back(pts[i]);
  return out;
}

// Cuts a polyline into its dashes; the pattern runs on across vertices.
std::vector<std::vector<Vec>> Dashes(const std::vector<Vec>& pts, const std::vector<double>& pattern) {
  std::vector<std::vector<Vec>> out;
  std::size_t k = 0;
  double left = std::max(pattern[0], 1e-3);
  bool on = true;
  std::vector<Vec> current{pts[0]};
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    Vec a = pts[i];
    const Vec b = pts[i + 1];
    double seg = Length(b - a);
    const Vec d = Normalized(b - a);
    while (seg > left) {
      a = a + d * left;
      seg -= left;
      if (on) {
        current.push_back(a);
        out.push_back(std::move(current));
        current.clear();
      } else {
        current = {a};
      }
      on = !on;
      k = (k + 1) % pattern.size();
      left = std::max(pattern[k], 1e-3);
    }
    left -= seg;
    if (on) current.push_back(b);
  }
  if (on && current.size() >= 2) out.push_back(std::move(current));
  return out;
}

// A stroke's cross-section: full alpha up to `inner` px from the centre line, falling to
// zero at `outer`; lines thinner than a pixel get a lower peak instead.
struct Profile {
  double inner = 0, outer = 1, peak = 1;
};
Profile ProfileFor(double width) {
  const double hw = width / 2;
  if (hw >= 0.5) return Profile{hw - 0.5, hw + 0.5, 1};
  return Profile{0, 1, std::max(width, 0.0)};
}

class OsMesaRenderer : public Renderer {
 public:
  OsMesaRenderer() {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (!context_) throw std::runtime_error("cannot create an OSMesa context");
    blend_separate_ = reinterpret_cast<BlendFuncSeparate>(OSMesaGetProcAddress("glBlendFuncSeparate"));
  }
  ~OsMesaRenderer() override { OSMesaDestroyContext(context_); }

  std::string name() const override { return "osmesa"; }

  void Begin(int width, int height, Color background) override {
    if (width < 1 || height < 1 || width > 8192 || height > 8192)
      throw InputError("image size " + std::to_string(width) + " x " + std::to_string(height) +
                       " px is outside 1..8192");
    width_ = width;
    height_ = height;
    buffer_.assign(static_cast<std::size_t>(width) * height * 4, 0);
    vertices_.clear();
    texts_.clear();
    layer_ = 0;
    clip_ = false;
    begun_ = true;
    MakeCurrent();
    glViewport(0, 0, width, height);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    // Pixel coordinates, y down; vertex z is the window depth.
    glOrtho(0, width, height, 0, 0, -1);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DITHER);
    glDisable(GL_LIGHTING);
    glDisable(GL_TEXTURE_2D);
    glShadeModel(GL_SMOOTH);
    glClearColor(background.r / 255.f, background.g / 255.f, background.b / 255.f, background.a / 255.f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glEnable(GL_BLEND);
    // "Over" for colour and alpha alike, so a transparent background composes correctly.
    if (blend_separate_)
      blend_separate_(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    else
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  }

  void SetClip(const Rect& r) override {
    CheckBegun();
    Flush();
    const int x0 = std::clamp(static_cast<int>(std::lround(r.x0)), 0, width_);
    const int x1 = std::clamp(static_cast<int>(std::lround(r.x1)), x0, width_);
    const int y0 = std::clamp(static_cast<int>(std::lround(r.y0)), 0, height_);
    const int y1 = std::clamp(static_cast<int>(std::lround(r.y1)), y0, height_);
    glEnable(GL_SCISSOR_TEST);
    glScissor(x0, height_ - y1, x1 - x0, y1 - y0);
    clip_ = true;
  }

  void ResetClip() override {
    CheckBegun();
    Flush();
    glDisable(GL_SCISSOR_TEST);
    clip_ = false;
  }

  void DrawPolyline(const std::vector<Point2d>& points, const LineStyle& style) override {
    CheckBegun();
    NextLayer();
    std::vector<Vec> piece;
    for (const Point2d& p : points) {
      if (std::isfinite(p.x) && std::isfinite(p.y)) {
        piece.push_back(Vec{p.x, p.y});
      } else {
        StrokeDashed(piece, style);
        piece.clear();
      }
    }
    StrokeDashed(piece, style);
  }

  void DrawSegments(const std::vector<Point2d>& endpoints, const LineStyle& style) override {
    CheckBegun();
    NextLayer();
    for (std::size_t i = 0; i + 1 < endpoints.size(); i += 2) {
      const Point2d a = endpoints[i], b = endpoints[i + 1];
      if (std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(b.x) && std::isfinite(b.y))
        StrokeDashed({Vec{a.x, a.y}, Vec{b.x, b.y}}, style);
    }
  }

  void FillPolygon(const std::vector<Point2d>& points, Color color) override {
    CheckBegun();
    NextLayer();
    std::vector<Vec> pts;
    for (const Point2d& p : points)
      if (std::isfinite(p.x) && std::isfinite(p.y) && (pts.empty() || Length(Vec{p.x, p.y} - pts.back()) > 1e-6))
        pts.push_back(Vec{p.x, p.y});
    while (pts.size() > 1 && Length(pts.front() - pts.back()) <= 1e-6) pts.pop_back();
    const std::size_t n = pts.size();
    if (n < 3) return;
    double area2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec a = pts[i], b = pts[(i + 1) % n];
      area2 += a.x * b.y - b.x * a.y;
    }
    if (std::abs(area2) < 1e-12) return;
    // In y-down pixels a positive area means clockwise on screen; outward is then to the left of travel.
    const double out_sign = area2 > 0 ? -1 : 1;
    std::vector<Vec> inner(n), outer(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec prev = pts[(i + n - 1) % n], here = pts[i], next = pts[(i + 1) % n];
      const Vec n0 = Normal(Normalized(here - prev)) * out_sign, n1 = Normal(Normalized(next - here)) * out_sign;
      const Vec m = Normalized(n0 + n1);
      const double scale = 1 / std::max(Dot(m, n1), 0.25);
      inner[i] = here - m * (0.5 * scale);
      outer[i] = here + m * (0.5 * scale);
    }
    for (std::size_t i = 1; i + 1 < n; ++i) Triangle(inner[0], inner[i], inner[i + 1], color, 1, 1, 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      Quad(inner[i], inner[j], outer[j], outer[i], color, 1, 1, 0, 0);
    }
  }

  void DrawText(const std::string& utf8, Point2d anchor, const TextStyle& style) override {
    CheckBegun();
    texts_.push_back(QueuedText{utf8, anchor, style});
  }

  RgbaImage Finish() override {
    CheckBegun();
    Flush();
    glFinish();
    RgbaImage image(width_, height_, 0);
    const std::size_t row = static_cast<std::size_t>(width_) * 4;
    // OpenGL's row 0 is the bottom one.
    for (int y = 0; y < height_; ++y)
      std::copy_n(buffer_.data() + static_cast<std::size_t>(height_ - 1 - y) * row, row,
                  image.pixels.data() + static_cast<std::size_t>(y) * row);
    for (const QueuedText& t : texts_) PaintText(&image, t.text, t.anchor, t.style);
    texts_.clear();
    begun_ = false;
    return image;
  }

 private:
  using BlendFuncSeparate = void (*)(GLenum, GLenum, GLenum, GLenum);
  struct QueuedText {
    std::string text;
    Point2d anchor;
    TextStyle style;
  };

  void CheckBegun() const {
    if (!begun_) throw std::logic_error("Renderer: drawing before Begin()");
  }

  void MakeCurrent() {
    if (OSMesaGetCurrentContext() == context_) {
      GLint w = 0, h = 0;
      void* buffer = nullptr;
      GLint format = 0;
      if (OSMesaGetColorBuffer(context_, &w, &h, &format, &buffer) && buffer == buffer_.data() && w == width_ &&
          h == height_)
        return;
    }
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw std::runtime_error("OSMesaMakeCurrent failed");
  }

  // Every call draws in front of the ones before; when the layers run out, the depth
  // buffer starts afresh (everything drawn so far is already in the colour buffer).
  void NextLayer() {
    if (layer_ + 1 >= kLayers) {
      Flush();
      glDisable(GL_SCISSOR_TEST);
      glClear(GL_DEPTH_BUFFER_BIT);
      if (clip_) glEnable(GL_SCISSOR_TEST);
      layer_ = 0;
    }
    ++layer_;
    base_depth_ = 1.0 - layer_ * kLayerSpan;
  }

  void Flush() {
    if (vertices_.empty()) return;
    MakeCurrent();
    glInterleavedArrays(GL_C4UB_V3F, 0, vertices_.data());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices_.size()));
    vertices_.clear();
  }

  // `alpha` is the fraction of the colour's opacity (0..1); the depth rises as it falls.
  void Emit(Vec p, Color c, double alpha) {
    const double a = std::clamp(alpha, 0.0, 1.0);
    vertices_.push_back(Vertex{c.r, c.g, c.b, static_cast<std::uint8_t>(std::lround(c.a * a)), static_cast<float>(p.x),
                               static_cast<float>(p.y),
                               static_cast<float>(base_depth_ + (1 - a) * 0.999 * kLayerSpan)});
  }
  void Triangle(Vec a, Vec b, Vec c, Color color, double aa, double ab, double ac) {
    Emit(a, color, aa);
    Emit(b, color, ab);
    Emit(c, color, ac);
    if (vertices_.size() >= kFlushVertices) Flush();
  }
  // a-b-c-d in order around the quad.
  void Quad(Vec a, Vec b, Vec c, Vec d, Color color, double aa, double ab, double ac, double ad) {
    Triangle(a, b, c, color, aa, ab, ac);
    Triangle(a, c, d, color, aa, ac, ad);
  }

  void StrokeDashed(const std::vector<Vec>& raw, const LineStyle& style) {
    if (raw.empty() || !(style.width > 0) || !std::isfinite(style.width)) return;
    const std::vector<Vec> pts = Simplify(raw, kSimplifyTolerance);
    double pattern_length = 0;
    bool valid_pattern = true;
    for (double d : style.dash) {
      valid_pattern = valid_pattern && std::isfinite(d) && d >= 0;
      pattern_length += d;
    }
    if (style.dash.empty() || !valid_pattern || pattern_length <= 0 || pts.size() < 2) {
      Stroke(pts, style);
      return;
    }
    for (const auto& dash : Dashes(pts, style.dash)) Stroke(dash, style);
  }

  // A disc, or the half of it on the side `towards` points to (a round cap).
  void Disc(Vec c, const Profile& pr, Color color, const Vec* towards = nullptr) {
    // Sides enough that the polygon strays less than a tenth of a pixel from the circle.
    const int n = std::clamp(static_cast<int>(std::ceil(kPi * std::sqrt(pr.outer / 0.2))), 6, 128);
    const double a_start = towards ? std::atan2(towards->y, towards->x) - kPi / 2 : 0;
    const int steps = towards ? (n + 1) / 2 : n;
    const double span = towards ? kPi : 2 * kPi;
    for (int i = 0; i < steps; ++i) {
      const double a0 = a_start + span * i / steps, a1 = a_start + span * (i + 1) / steps;
      const Vec u0{std::cos(a0), std::sin(a0)}, u1{std::cos(a1), std::sin(a1)};
      if (pr.inner > 0) {
        Triangle(c, c + u0 * pr.inner, c + u1 * pr.inner, color, pr.peak, pr.peak, pr.peak);
        Quad(c + u0 * pr.inner, c + u1 * pr.inner, c + u1 * pr.outer, c + u0 * pr.outer, color, pr.peak, pr.peak, 0, 0);
      } else {
        Triangle(c, c + u0 * pr.outer, c + u1 * pr.outer, color, pr.peak, 0, 0);
      }
    }
  }

  // One polyline: runs with mitred joints, round joints where it turns sharply, caps at the ends.
  void Stroke(const std::vector<Vec>& pts, const LineStyle& style) {
    const Profile pr = ProfileFor(style.width);
    if (pts.empty()) return;
    double total = 0;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) total += Length(pts[i + 1] - pts[i]);
    if (pts.size() < 2 || total < 0.05) {  // a dot
      if (style.cap == LineCap::kRound) Disc(pts[0], pr, style.color);
      return;
    }
    const bool round = style.cap == LineCap::kRound;
    std::size_t start = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const bool last = i + 1 == pts.size();
      const bool sharp = !last && Dot(Normalized(pts[i] - pts[i - 1]), Normalized(pts[i + 1] - pts[i])) < kSharpTurn;
      if (last || sharp) {
        Run(pts, start, i, style.color, pr, !round && start == 0, !round && last);
        if (sharp) Disc(pts[i], pr, style.color);
        start = i;
      }
    }
    if (round) {
      const Vec back = Normalized(pts[0] - pts[1]), ahead = Normalized(pts.back() - pts[pts.size() - 2]);
      Disc(pts.front(), pr, style.color, &back);
      Disc(pts.back(), pr, style.color, &ahead);
    }
  }

  // Points a..b (inclusive) as one strip: outer-left, inner-left, inner-right, outer-right
  // per point. Butt ends are feathered across the end too (half a pixel in, half out).
  void Run(const std::vector<Vec>& all, std::size_t a, std::size_t b, Color color, const Profile& pr, bool butt_start,
           bool butt_end) {
    std::vector<Vec> pts(all.begin() + a, all.begin() + b + 1);
    const std::size_t n = pts.size();
    const Vec d0 = Normalized(pts[1] - pts[0]), d1 = Normalized(pts[n - 1] - pts[n - 2]);
    if (butt_start) pts[0] = pts[0] + d0 * std::min(0.5, Length(pts[1] - pts[0]) / 2);
    if (butt_end) pts[n - 1] = pts[n - 1] - d1 * std::min(0.5, Length(pts[n - 1] - pts[n - 2]) / 2);
    std::vector<Vec> off(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec n0 = Normal(Normalized(pts[i > 0 ? i : 1] - pts[i > 0 ? i - 1 : 0]));
      const Vec n1 = Normal(Normalized(pts[i + 1 < n ? i + 1 : n - 1] - pts[i + 1 < n ? i : n - 2]));
      const Vec m = Normalized(n0 + n1);
      off[i] = m * (1 / std::max(Dot(m, n1), 0.5));
    }
    auto row = [&](std::size_t i, Vec shift, double fade) {
      const Vec p = pts[i] + shift;
      return std::array<std::pair<Vec, double>, 4>{{{p + off[i] * pr.outer, 0},
                                                    {p + off[i] * pr.inner, pr.peak * fade},
                                                    {p - off[i] * pr.inner, pr.peak * fade},
                                                    {p - off[i] * pr.outer, 0}}};
    };
    auto band = [&](const auto& r0, const auto& r1) {
      for (int k = 0; k < 3; ++k) {
        if (k == 1 && pr.inner <= 0) continue;
        Quad(r0[k].first, r1[k].first, r1[k + 1].first, r0[k + 1].first, color, r0[k].second, r1[k].second,
             r1[k + 1].second, r0[k + 1].second);
      }
    };
    for (std::size_t i = 0; i + 1 < n; ++i) band(row(i, {}, 1), row(i + 1, {}, 1));
    if (butt_start) band(row(0, d0 * -1.0, 0), row(0, {}, 1));
    if (butt_end) band(row(n - 1, {}, 1), row(n - 1, d1, 0));
  }

  OSMesaContext context_ = nullptr;
  BlendFuncSeparate blend_separate_ = nullptr;
  std::vector<std::uint8_t> buffer_;  // OpenGL's colour buffer, bottom row first
  std::vector<Vertex> vertices_;      // triangles not yet drawn
  std::vector<QueuedText> texts_;
  int width_ = 0, height_ = 0;
  int layer_ = 0;
  double base_depth_ = 1;
  bool clip_ = false;
  bool begun_ = false;
};

}  // namespace

std::unique_ptr<Renderer> MakeOsMesaRenderer() { return std::make_unique<OsMesaRenderer>(); }

}  // namespace internal
}  // namespace twinsim
