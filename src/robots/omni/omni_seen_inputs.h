// The inputs an omni model's fit saw (issue 64; docs/identification.md, "Intervals out of
// the fit's reach"): where a prediction's inputs lie far from every one the model was
// fitted on, its own error grows, and so must its intervals.
//
// A frame's input is the wheel speeds of the command acting in it and of the body's
// velocity, u = (J c, J v) (rad/s, 2n numbers; J = omni_kinematics.h's wheels_from_body):
// the motors' operating point, asked and reached, in one unit for every axis (a turn of
// omega moves each wheel as a drive of omega times its distance does). A frame's
// distance from the seen inputs is the distance from u to the nearest seen one over
// `scale` (the seen commands' root-mean-square wheel speed), so 1 is as far as a typical
// command from standing still. The seen ones are a farthest-point subsample of the fit's
// frames (at most kMaxSeenInputs), every fit frame within `covering` of one of them.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/pose.h"

namespace twinsim {

struct OmniSeenInputs {
  double scale = 0;                    // rad/s; 0: none seen (empty)
  double covering = 0;                 // every fit frame lies within this distance of a point
  std::vector<Eigen::VectorXd> points;  // each 2n long: (J c, J v), rad/s

  bool empty() const { return points.empty(); }
  // The distance of input u (2n long) from the nearest point, over `scale`; 0 when empty.
  double Distance(const Eigen::VectorXd& u) const;
};

inline constexpr int kMaxSeenInputs = 256;

// A frame's input: the wheel speeds of `command` and of `velocity` (robot frame) under
// J (n x 3).
Eigen::VectorXd SeenInputFeature(const Eigen::MatrixXd& wheels_from_body, const Twist2& command,
                                 const Twist2& velocity);

// The seen inputs of the fit's frames `inputs` (each 2n long): the first, then each
// next the input farthest from those taken (the first of equals), up to `most`; the
// scale is the root-mean-square norm of their command halves (at least 1e-3 rad/s).
// Empty without inputs.
OmniSeenInputs MakeSeenInputs(const std::vector<Eigen::VectorXd>& inputs, int most = kMaxSeenInputs);

}  // namespace twinsim
