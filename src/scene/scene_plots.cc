#include "scene/scene_plots.h"

#include <cmath>

#include "control/tracking_plots.h"

namespace twinsim {
namespace {

// A title naming the plot unless the spec gives one, placeholders filled in.
std::string ArmPlotTitle(const ArmPlotSpec& spec, const ArmScene& scene, const std::string& backend,
                         const std::string& what) {
  PlotSpec generic;
  generic.title = spec.title.empty() ? "{scene} ({backend}): " + what : spec.title;
  return PlotTitle(generic, scene.name, backend, scene.seed);
}

}  // namespace

RgbaImage RenderScenePlot(const ScenePlot& plot, Renderer& renderer) {
  if (const auto* path = std::get_if<PathPlot>(&plot.plot)) return RenderPathPlot(*path, renderer);
  return RenderSeriesPlot(std::get<SeriesPlot>(plot.plot), renderer);
}

PathPlot ScenePathPlot(const PlotSpec& spec, const Scene& scene, const SimulationResult& result,
                       const std::string& backend) {
  PathPlot plot;
  plot.title = PlotTitle(spec, scene.name, backend, scene.seed);
  plot.width = spec.width;
  plot.height = spec.height;
  plot.orientation_every = spec.orientation_every;
  const WorldRect field{-scene.field.length / 2, scene.field.length / 2, -scene.field.width / 2, scene.field.width / 2};
  plot.field = field;
  if (spec.region_is_field) {
    const double m = 0.15;  // m, so that the outline is not on the frame
    plot.region = WorldRect{field.x_min - m, field.x_max + m, field.y_min - m, field.y_max + m};
  } else {
    plot.region = spec.region;
  }
  const bool single = result.frames.size() == 1;
  // Robots on several backends: each path names its robot's (the title only says mixed).
  bool mixed = false;
  for (const std::string& b : result.robot_backends) mixed = mixed || b != result.robot_backends.front();
  const std::string source = !spec.source.empty() ? spec.source : single ? "both" : "truth";
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    const std::vector<FrameRecord>& frames = result.frames[i];
    const std::string robot =
        result.robot_names[i] + (mixed && i < result.robot_backends.size() ? " on " + result.robot_backends[i] : "");
    if (source == "truth" || source == "both") {
      PlotPath p;
      p.name = single ? "truth" : source == "both" ? robot + " truth" : robot;
      for (std::size_t k = 0; k < frames.size(); ++k) {
        if (!frames[k].present) continue;  // off the field
        p.poses.push_back(frames[k].truth);
        p.frames.push_back(static_cast<int>(k));
      }
      plot.paths.push_back(std::move(p));
    }
    if (source == "seen" || source == "both") {
      PlotPath p;
      const int late = i < scene.robots.size() ? scene.robots[i].model.vision_delay_frames : 0;
      const std::string what = "seen by the observer (" + std::to_string(late) + (late == 1 ? " frame" : " frames") + " late)";
      p.name = single ? what : source == "both" ? robot + " " + what : robot + ", " + what;
      // Numbered by the frame the camera captured them in, so that both paths tick the
      // same moments and the ticks differ only by what the camera got wrong.
      for (std::size_t k = 0; k < frames.size(); ++k) {
        if (!frames[k].observed) continue;
        p.poses.push_back(frames[k].seen);
        p.frames.push_back(static_cast<int>(k) - late);
      }
      plot.paths.push_back(std::move(p));
    }
  }
  // The ball's true path, without heading ticks (a NaN heading draws none).
  if (!result.ball.empty()) {
    // Beside the ball a lone robot's paths are named after it.
    if (single)
      for (PlotPath& robot : plot.paths) robot.name = result.robot_names[0] + " " + robot.name;
    PlotPath p;
    p.name = "ball";
    for (std::size_t k = 0; k < result.ball.size(); ++k) {
      const Eigen::Vector3d& b = result.ball[k].truth.position;
      p.poses.push_back(Pose2{b.x(), b.y(), std::nan("")});
      p.frames.push_back(static_cast<int>(k));
    }
    plot.paths.push_back(std::move(p));
  }
  return plot;
}

std::vector<ScenePlot> ScenePlots(const Scene& scene, const SimulationResult& result, const std::string& backend) {
  std::vector<ScenePlot> plots;
  for (const PlotSpec& spec : scene.plots) plots.push_back({spec.file, ScenePathPlot(spec, scene, result, backend)});
  return plots;
}

std::vector<ScenePlot> ArmScenePlots(const ArmScene& scene, const TrackingTrial& trial, const std::string& backend) {
  std::vector<ScenePlot> plots;
  for (const ArmPlotSpec& spec : scene.plots) {
    if (spec.type == "tool_path") {
      PathPlot plot = ToolPathPlot(trial, scene.plant, scene.task.writing.tool,
                                   ArmPlotTitle(spec, scene, backend, "tool point path"));
      plot.width = spec.width, plot.height = spec.height;
      plots.push_back({spec.file, std::move(plot)});
    } else if (spec.type == "joint_torques") {
      const std::string stem = spec.file.substr(0, spec.file.size() - 4);
      for (int j = 0; j < scene.plant.dof(); ++j) {
        SeriesPlot plot = JointTorquePlot(
            trial, scene.plant, j, ArmPlotTitle(spec, scene, backend, "joint " + std::to_string(j + 1) + " torque"));
        plot.width = spec.width, plot.height = spec.height;
        plots.push_back({stem + "_joint" + std::to_string(j + 1) + ".png", std::move(plot)});
      }
    } else {
      SeriesPlot plot = TrackingErrorPlot(trial, scene.plant, ArmPlotTitle(spec, scene, backend, "tracking error"));
      plot.width = spec.width, plot.height = spec.height;
      plots.push_back({spec.file, std::move(plot)});
    }
  }
  return plots;
}

}  // namespace twinsim
