// The Newtonian model that a residual ("hybrid") omni predictor corrects, carried along a
// robot's poses.
//
// A residual predictor (`twinsim train --residual`, docs/learning.md) predicts the pose H
// frames ahead as the Newtonian model's own prediction plus a learned correction. The
// model runs as `replay`'s tracker does (analysis/omni_replay.h): one robot on one of
// the engines (analytic, ode, bullet) with its on-board controller and the model file's
// effects, stepped a frame at a time under the commands that act, its pose corrected to
// every known pose of the robot (measured in training and replay, the predictor's own in
// simulation) while its velocity and controller state stay its own. Each correction is
// the model's one-frame error there; the last few are inputs of the predictor
// (omni_features.h), so it sees how the model has been wrong lately.
//
// Training, the learned backend, `replay`, `compare` and a go_to_pose behaviour all use
// this one class, so the inputs a predictor was trained on are the inputs it gets.
//
//   NominalOmniTrack track(model, "analytic", 30.0, 2, 0);
//   track.Reset(pose, velocity);
//   for each frame: track.Step(acting); track.Correct(measured);
//   Pose2 in4 = track.Lookahead(acting_next4, 4);   // the model's own 4-frame prediction
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "robots/omni/omni_model.h"
#include "sim/omni_backend.h"

namespace twinsim {

// Frames the track runs along a log before its errors and state are trusted as inputs.
inline constexpr int kNominalWarmUpFrames = 15;

class NominalOmniTrack {
 public:
  // The model on `engine` (analytic, ode, bullet) at `frame_rate` Hz in `substeps`
  // physics steps per frame (0: the loop's default, DefaultPhysicsSubsteps), keeping its
  // last `errors` one-frame errors. Throws InputError for an unknown or uncompiled engine.
  NominalOmniTrack(const OmniModel& model, const std::string& engine, double frame_rate, int substeps, int errors);
  // A copy is an independent track in the same state.
  NominalOmniTrack(const NominalOmniTrack& other);
  NominalOmniTrack& operator=(const NominalOmniTrack& other);
  NominalOmniTrack(NominalOmniTrack&&) = default;
  NominalOmniTrack& operator=(NominalOmniTrack&&) = default;

  // Puts the model at `pose` moving at `velocity` (robot frame), its controller settled
  // on it; the errors are zero.
  void Reset(const Pose2& pose, const Twist2& velocity);
  // One frame under the command acting now. Returns the model's pose at the next frame
  // (what Correct() compares with). Throws CheckFailed when the model runs away.
  Pose2 Step(const Twist2& acting);
  // The newest frame's pose is `pose`: its error is `pose` minus the model's prediction of
  // it, and the model moves there (velocity and controller state kept).
  void Correct(const Pose2& pose);
  // The model's pose `frames` frames from now under acting[0 .. frames-1], the track
  // left as it was. Throws CheckFailed when the model runs away.
  Pose2 Lookahead(const Twist2* acting, int frames);

  Pose2 pose() const { return backend_->pose(0); }
  Twist2 velocity() const { return backend_->velocity(0); }  // robot frame
  // The last errors (field frame: dx, dy, dtheta), oldest first; frames without a
  // correction count as zero.
  const std::vector<Eigen::Vector3d>& errors() const { return errors_; }

  NominalTrackState Save() const;
  void Restore(const NominalTrackState& state);

 private:
  OmniModel model_;
  std::string engine_;
  double frame_rate_ = 0;
  int substeps_ = 0;
  std::unique_ptr<OmniBackend> backend_;
  Pose2 predicted_;
  std::vector<Eigen::Vector3d> errors_;
};

// A fingerprint of everything in `model` (its complete model file): a residual predictor
// keeps the one of the model it was trained over and refuses another.
std::string NominalModelFingerprint(const OmniModel& model);

}  // namespace twinsim
