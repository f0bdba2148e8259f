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
// With OmniReplayState::kObserver the model is carried by its observer instead
// (estimation/omni_observer.h, the filter `replay` and identify predict from): each known
// pose corrects the pose, the model's velocity and the driving noise's slip by the
// filter's gain, so the model's state is the estimate a physics-only replay starts from,
// and a correction learned on top of it starts from there too. Its errors are then the
// filter's innovations (the pose minus the filter's prediction of it); its velocity is
// the body's (the model's plus the slip).
//
// A predictor rolling out on its own moves the track to each pose it predicts (Follow);
// under the observer, a measurement of the same frame (Correct) first takes that move
// back, so that the filter is corrected from the model's own prediction, as in training.
//
//   NominalOmniTrack track(model, "analytic", 30.0, 2, 0);
//   track.Reset(pose, velocity);
//   for each frame: track.Step(acting); track.Correct(measured);
//   Pose2 in4 = track.Lookahead(acting_next4, 4);   // the model's own 4-frame prediction
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "estimation/omni_observer.h"
#include "robots/omni/omni_model.h"
#include "sim/omni_backend.h"

namespace twinsim {

// Frames the track runs along a log before its errors and state are trusted as inputs.
inline constexpr int kNominalWarmUpFrames = 15;

// What changes inside the Newtonian model that a residual predictor corrects
// (NominalOmniTrack): the model's own backend state (or, carried by its observer, the
// filter's whole state), the pose it predicted for the newest frame, and its recent
// errors (field frame: dx, dy m, dtheta rad; the newest last).
struct NominalTrackState {
  std::vector<OmniRobotState> backend;
  std::optional<OmniObserverState> observer;
  std::optional<OmniObserverState> before_follow;  // the observer before this frame's Follow
  Pose2 predicted;
  std::vector<Eigen::Vector3d> errors;
};

class NominalOmniTrack {
 public:
  // The model on `engine` (analytic, ode, bullet) at `frame_rate` Hz in `substeps`
  // physics steps per frame (0: the loop's default, DefaultPhysicsSubsteps), keeping its
  // last `errors` one-frame errors, carried along the poses by `state` (the open-loop
  // tracker, or its observer). Throws InputError for an unknown or uncompiled engine.
  NominalOmniTrack(const OmniModel& model, const std::string& engine, double frame_rate, int substeps, int errors,
                   OmniReplayState state = OmniReplayState::kTracker);
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
  // The newest frame's pose is `pose`, measured: its error is `pose` minus the model's
  // prediction of it, and the model moves there (the tracker: velocity and controller
  // state kept; the observer: its update, after taking back this frame's Follow).
  void Correct(const Pose2& pose);
  // The newest frame's pose is `pose`, a predictor's own: the model moves there (the
  // tracker: as Correct; the observer: velocity, slip and covariance kept, no error).
  void Follow(const Pose2& pose);
  // The model's pose `frames` frames from now under acting[0 .. frames-1], the track
  // left as it was. Throws CheckFailed when the model runs away.
  Pose2 Lookahead(const Twist2* acting, int frames);

  Pose2 pose() const;
  Twist2 velocity() const;  // robot frame
  OmniReplayState state() const { return state_; }
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
  OmniReplayState state_ = OmniReplayState::kTracker;
  std::unique_ptr<OmniBackend> backend_;    // the tracker's model (null under the observer)
  std::unique_ptr<OmniObserver> observer_;  // the observer, which holds the model (null for the tracker)
  Pose2 predicted_;
  std::optional<OmniObserverState> before_follow_;  // the observer before this frame's Follow
  std::vector<Eigen::Vector3d> errors_;
};

// A fingerprint of everything in `model` (its complete model file): a residual predictor
// keeps the one of the model it was trained over and refuses another.
std::string NominalModelFingerprint(const OmniModel& model);

}  // namespace twinsim
