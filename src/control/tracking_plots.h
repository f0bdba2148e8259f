// The plots of a tracking trial (control/computed_torque.h), as seed 001 shows the
// writing task: the tool point's path in the writing plane, reference against realised
// (Fig. 6); per joint the controller's output beside the model's torque over time, with
// the effort limit, so that saturation shows (Fig. 7); and every joint's tracking error.
// They build plain SeriesPlot / PathPlot structs (render/plot.h); drawing is the caller's.
//
//   TrackingTrial trial = RunTrackingTrial(plant, hat, reference, options);
//   WritePng("path.png", RenderPathPlot(ToolPathPlot(trial, plant, tool, "TUE"), *renderer));
#pragma once

#include <Eigen/Core>
#include <string>

#include "control/computed_torque.h"
#include "render/plot.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// The tool point (`tool` in the last link's frame, m) of `plant` along the trial's
// reference and realised joint paths, in the base frame's y-z plane as seen from behind
// the arm looking along +x: horizontal -y, vertical z (m), so letters read left to right.
PathPlot ToolPathPlot(const TrackingTrial& trial, const ArmModel& plant, const Eigen::Vector3d& tool,
                      const std::string& title);

// Joint `joint` (0-based): the command sent, the model-based part of the controller's
// output, the demand before clamping (where it differs from the command) and the
// plant's effort limit (where given), N·m or N over s. Throws std::out_of_range for a
// joint that does not exist.
SeriesPlot JointTorquePlot(const TrackingTrial& trial, const ArmModel& plant, int joint, const std::string& title);

// q_ref - q of every joint over time, in mrad (mm for prismatic joints).
SeriesPlot TrackingErrorPlot(const TrackingTrial& trial, const ArmModel& plant, const std::string& title);

}  // namespace twinsim
