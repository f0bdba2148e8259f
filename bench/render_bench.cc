// Rendering a path plot: 1200 x 900 px, 4 paths of 10,000 poses each (issue 4's goal:
// render and encode in at most 100 ms).
//
//   build/render_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// BM_RenderAndEncode: RenderPathPlot (layout, OSMesa, text) and EncodePng, the goal.
// BM_Render, BM_EncodePng: the two halves.
#include <benchmark/benchmark.h>
#include <png.h>

#include <cmath>
#include <cstring>

#include "core/rng.h"
#include "io/png_image.h"
#include "render/plot.h"
#include "render/renderer.h"

namespace twinsim {
namespace {

// Four drives over a 6 x 4 m patch: smooth curves (sums of sines), the later ones with
// a few millimetres of camera-like noise, heading turning along.
PathPlot BenchPlot() {
  PathPlot plot;
  plot.title = "4 paths x 10,000 poses";
  const char* names[] = {"measured", "ODE", "Bullet", "learned model"};
  std::uint64_t state = 12345;
  auto noise = [&] {  // uniform in [-1, 1], deterministic
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 4503599627370496.0 - 1;
  };
  for (int k = 0; k < 4; ++k) {
    PlotPath p;
    p.name = names[k];
    for (int i = 0; i < 10000; ++i) {
      const double t = i / 60.0;  // s, 60 fps
      const double e = 0.02 * k;
      p.poses.push_back(Pose2{3.0 * std::sin(0.11 * t + e) + 0.4 * std::sin(0.53 * t) + (k ? 0.003 * noise() : 0),
                              2.0 * std::sin(0.17 * t + 2 * e) + 0.3 * std::cos(0.71 * t) + (k ? 0.003 * noise() : 0),
                              0.3 * t + e});
    }
    plot.paths.push_back(std::move(p));
  }
  return plot;
}

void BM_RenderAndEncode(benchmark::State& state) {
  if (!RenderingCompiled()) return state.SkipWithError("built without OSMesa");
  const PathPlot plot = BenchPlot();
  auto renderer = MakeRenderer("osmesa");
  RenderPathPlot(plot, *renderer);  // LLVM compiles llvmpipe's shaders once per context
  for (auto _ : state) benchmark::DoNotOptimize(EncodePng(RenderPathPlot(plot, *renderer)));
}
BENCHMARK(BM_RenderAndEncode)->Unit(benchmark::kMillisecond);

void BM_Render(benchmark::State& state) {
  if (!RenderingCompiled()) return state.SkipWithError("built without OSMesa");
  const PathPlot plot = BenchPlot();
  auto renderer = MakeRenderer("osmesa");
  RenderPathPlot(plot, *renderer);
  for (auto _ : state) benchmark::DoNotOptimize(RenderPathPlot(plot, *renderer));
}
BENCHMARK(BM_Render)->Unit(benchmark::kMillisecond);

void BM_EncodePng(benchmark::State& state) {
  if (!RenderingCompiled()) return state.SkipWithError("built without OSMesa");
  auto renderer = MakeRenderer("osmesa");
  const RgbaImage image = RenderPathPlot(BenchPlot(), *renderer);
  std::size_t bytes = 0;
  for (auto _ : state) bytes = EncodePng(image).size();
  state.counters["kB"] = bytes / 1000.0;
}
BENCHMARK(BM_EncodePng)->Unit(benchmark::kMillisecond);



}  // namespace
}  // namespace twinsim

BENCHMARK_MAIN();
