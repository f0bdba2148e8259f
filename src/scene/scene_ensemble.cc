#include "scene/scene_ensemble.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <mutex>

#include "core/covariance_root.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "core/parallel.h"
#include "learning/omni_predictor.h"
#include "robots/omni/omni_log.h"

namespace twinsim {

OmniEnsemble RunOmniEnsemble(const Scene& scene, const std::string& backend, const std::string& predictor,
                             const OmniEnsembleOptions& options, const std::function<void(int, int)>& progress) {
  if (options.samples < 1) throw InputError("--samples must be 1 or more, got " + std::to_string(options.samples));
  if (options.jobs < 0) throw InputError("--jobs must be 0 (one per core) or more");
  OmniBackendOptions backend_options;
  if (!predictor.empty()) backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(predictor));
  bool any = false;
  for (const SceneRobot& r : scene.robots)
    any = any || SimulatedRobotModel(scene, r, RobotChoice(r, backend, backend_options)).driving_noise.simulated;
  if (!any) {
    throw InputError(SourceLocation{scene.path},
                     "--samples needs a robot that draws driving noise, else every sample is the same run: "
                     "--driving-noise on, a model with driving_noise.simulated (identify writes one), or a learned "
                     "robot's predictor with a driving noise (train writes one)");
  }
  const int frames = scene.num_frames();
  OmniEnsemble out;
  out.paths.resize(static_cast<std::size_t>(options.samples));
  std::vector<SimulationResult> first(1);
  int done = 0;
  std::mutex progress_mutex;  // the callback is the caller's: one thread at a time
  auto first_path = [](const SimulationResult& r) {
    std::vector<Pose2> path;
    for (const FrameRecord& f : r.frames[0]) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      path.push_back(f.present ? f.truth : Pose2{nan, nan, nan});
    }
    return path;
  };
  // Sample -1: no driving noise at all, the path the fan spreads around.
  ParallelFor(options.samples + 1, options.jobs, [&](int k) {
    if (k == options.samples) {
      Scene still = scene;
      still.driving_noise = "off";
      out.without_noise = first_path(MakeSimulation(still, backend, backend_options).Run(frames));
      return;
    }
    Simulation sim = MakeSimulation(scene, backend, backend_options);
    sim.SetDrivingNoiseSample(scene.seed, static_cast<std::uint64_t>(k));
    if (options.parameter_draws && k > 0) sim.DrawModelParameters(scene.seed, static_cast<std::uint64_t>(k));
    SimulationResult r = sim.Run(frames);
    out.paths[static_cast<std::size_t>(k)] = first_path(r);
    if (k == 0) first[0] = std::move(r);
    const std::lock_guard<std::mutex> lock(progress_mutex);
    ++done;
    if (progress) progress(done, options.samples);
  });
  out.first = std::move(first[0]);
  for (const FrameRecord& f : out.first.frames[0]) out.t.push_back(f.t);
  out.robot = out.first.robot_names.empty() ? std::string() : out.first.robot_names[0];
  return out;
}

std::string FormatEnsembleCsv(const OmniEnsemble& e) {
  // Per frame, the samples' poses.
  std::vector<std::vector<Pose2>> by_frame(e.t.size());
  for (std::size_t f = 0; f < e.t.size(); ++f)
    for (const auto& path : e.paths) by_frame[f].push_back(path[f]);
  return FormatPoseSamplesCsv(e.t, by_frame);
}

SeriesPlot EnsemblePlot(const OmniEnsemble& e, double mark_seconds) {
  SeriesPlot plot;
  char every_label[32];
  std::snprintf(every_label, sizeof every_label, "%g s", mark_seconds);
  plot.title = e.robot + ": " + std::to_string(e.paths.size()) + " samples under its driving noise; ellipses hold 50 % " +
               "and 90 % of them, every " + every_label;
  plot.x_label = "x [m]";
  plot.y_label = "y [m]";
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  // One path as a series, the bounds widened by it.
  auto path_series = [&](const std::vector<Pose2>& path, PlotSeries s) {
    for (const Pose2& p : path) {
      s.x.push_back(p.x);
      s.y.push_back(p.y);
      if (std::isfinite(p.x)) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
    plot.series.push_back(std::move(s));
  };
  for (std::size_t k = 0; k < e.paths.size(); ++k)
    path_series(e.paths[k], k == 0 ? PlotSeries{"sample 0 (the plain run)", {}, {}, false, std::nullopt}
                                   : PlotSeries{"", {}, {}, false, 0xbbbbbb, false});
  std::rotate(plot.series.begin(), plot.series.begin() + 1, plot.series.end());  // sample 0 drawn last, on top
  if (!e.without_noise.empty()) path_series(e.without_noise, PlotSeries{"without driving noise", {}, {}, false, 0x000000});
  // The ellipses: at each mark, a Gaussian fitted to the samples' positions.
  const double period = e.t.size() > 1 ? e.t[1] - e.t[0] : 1.0;
  const int every = std::max(1, static_cast<int>(std::lround(mark_seconds / period)));
  PlotSeries inner{"50 % of the samples", {}, {}, false, 0x0072B2}, outer{"90 %", {}, {}, false, 0xD55E00};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t f = static_cast<std::size_t>(every); f < e.t.size(); f += static_cast<std::size_t>(every)) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    int n = 0;
    for (const auto& path : e.paths) {
      if (!std::isfinite(path[f].x)) continue;
      mean += Eigen::Vector2d(path[f].x, path[f].y);
      ++n;
    }
    if (n < 3) continue;
    mean /= n;
    for (const auto& path : e.paths) {
      if (!std::isfinite(path[f].x)) continue;
      const Eigen::Vector2d d = Eigen::Vector2d(path[f].x, path[f].y) - mean;
      cov += d * d.transpose() / (n - 1);
    }
    const Eigen::Matrix2d root = CovarianceRoot(cov);
    for (auto [series, p] : {std::pair{&inner, 0.5}, std::pair{&outer, 0.9}}) {
      const double r = std::sqrt(-2 * std::log(1 - p));  // chi-square, 2 degrees of freedom
      for (int j = 0; j <= 48; ++j) {
        const double a = 2 * kPi * j / 48;
        const Eigen::Vector2d q = mean + r * root * Eigen::Vector2d(std::cos(a), std::sin(a));
        series->x.push_back(q.x());
        series->y.push_back(q.y());
        x0 = std::min(x0, q.x()), x1 = std::max(x1, q.x()), y0 = std::min(y0, q.y()), y1 = std::max(y1, q.y());
      }
      series->x.push_back(nan);  // break the line between ellipses
      series->y.push_back(nan);
    }
  }
  plot.series.push_back(inner);
  plot.series.push_back(outer);
  // Equal scales: widen the shorter side of the region to the plot area's shape.
  if (x1 >= x0 && y1 >= y0) {
    const double margin = 0.05 * std::max({x1 - x0, y1 - y0, 0.1});
    x0 -= margin, x1 += margin, y0 -= margin, y1 += margin;
    const double aspect = static_cast<double>(plot.width) / plot.height;
    if ((x1 - x0) / (y1 - y0) < aspect) {
      const double w = (y1 - y0) * aspect, c = 0.5 * (x0 + x1);
      x0 = c - w / 2, x1 = c + w / 2;
    } else {
      const double h = (x1 - x0) / aspect, c = 0.5 * (y0 + y1);
      y0 = c - h / 2, y1 = c + h / 2;
    }
    plot.range = WorldRect{x0, x1, y0, y1};
  }
  return plot;
}

}  // namespace twinsim
