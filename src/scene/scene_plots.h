// The plots a scene's `plots:` list asks `twinsim run` for (docs/rendering.md), built
// from a run's results as plain PathPlot / SeriesPlot structs (render/plot.h), each with
// the file it goes to, so that a command, a binding or a batch runner draws the same
// PNGs. An omni scene draws robot paths on the field: each robot's true path and/or
// what its observer saw, late by its vision delay. An arm scene draws the tool point's
// path, the torques per joint and the tracking error (control/tracking_plots.h).
//
//   for (const ScenePlot& p : ScenePlots(scene, result, "ode"))
//     WritePng(dir + "/" + p.file, RenderScenePlot(p, *renderer));
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "control/computed_torque.h"
#include "io/png_image.h"
#include "render/plot.h"
#include "render/plot_spec.h"
#include "render/renderer.h"
#include "scene/arm_scene.h"
#include "scene/scene.h"
#include "sim/omni_simulation.h"

namespace twinsim {

// One PNG to draw: the file it goes to and what it shows.
struct ScenePlot {
  std::string file;                         // a plain file name in the output folder
  std::variant<PathPlot, SeriesPlot> plot;
};

// Draws `plot`. Throws what RenderPathPlot / RenderSeriesPlot throw.
RgbaImage RenderScenePlot(const ScenePlot& plot, Renderer& renderer);

// The path plot `spec` asks for of a run of `scene` on `backend`: each robot's true
// path (every frame) and/or what its observer saw (the frames that arrived, numbered by
// the frame the camera captured them in), on the field (m). On a field of several
// backends (result.robot_backends differ) each robot's paths say its: "blue0 on ode".
PathPlot ScenePathPlot(const PlotSpec& spec, const Scene& scene, const SimulationResult& result,
                       const std::string& backend);

// Every plot of the omni scene's `plots:` list, in order.
std::vector<ScenePlot> ScenePlots(const Scene& scene, const SimulationResult& result, const std::string& backend);

// Every plot of the arm scene's `plots:` list, in order, for a trial on `backend`:
// tool_path and tracking_error one each, joint_torques one per joint (the file's stem
// with `_joint<j>` before .png).
std::vector<ScenePlot> ArmScenePlots(const ArmScene& scene, const TrackingTrial& trial, const std::string& backend);

}  // namespace twinsim
