// What the omni loop (sim/omni_simulation.h) steps, one camera frame at a time, with
// commands it has already delayed: the robots' plant. The same seam as ArmBackend for
// the arm.
//
// Two kinds implement it:
//   - the Newtonian backend (sim/newtonian_omni_backend.h): an OmniEngine (analytic,
//     ode, bullet: bodies, joints and contacts only) with the robots' on-board
//     controller, encoders, motors and effects on top, cut into physics steps;
//   - the learned backend (backends/learned/learned_omni_backend.h): a predictor learned
//     from the real robot's logs, which has learned all of that with the bodies.
// All of them take the same calls, so the loop, replay, the observer and the tests treat
// them alike. MakeOmniBackend() (backends/omni_backend_factory.h) builds any by name.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/pose.h"
#include "core/rng.h"
#include "engines/omni_engine.h"
#include "robots/omni/omni_model.h"
#include "robots/omni/onboard_controller.h"

namespace twinsim {

// How the loop slices time.
struct FrameTiming {
  double frame_rate = 30;    // Hz, camera frames
  int physics_substeps = 10;  // physics steps per frame
  double frame_dt() const { return 1.0 / frame_rate; }
  double physics_dt() const { return frame_dt() / physics_substeps; }
};

// The physics step the loop uses when a scene does not say: the finest step of at
// most 1/300 s that divides the frame (grSim: 5 steps per 60 fps frame).
int DefaultPhysicsSubsteps(double frame_rate);

struct NominalTrackState;

// Everything that changes about one robot inside a backend.
struct OmniRobotState {
  OmniBodyState body;
  std::vector<double> engine_snapshot;  // OmniEngine::SaveExact(), when the engine has one
  OnboardControllerState controller;
  int ticks_until_control = 0;  // physics steps until the next controller tick
  bool encoders_pending = false;  // the last physics step's wheel turn is not counted yet

  // Effects (robots/omni/omni_effects.h).
  double clock = 0;                                  // s since Reset
  std::vector<std::pair<double, Twist2>> received;   // (s, command) not yet acting (time_delay)
  Twist2 acting;                                     // the command the firmware acts on
  Twist2 series_lagged;                              // after motor_lag's lag in series (`series`)
  Twist2 lagged;                                     // after motor_lag
  Twist2 gripped;                                    // after traction_limit: the set-point the grip lets the body follow

  // The learned backend's window: the newest last.
  std::vector<Pose2> pose_history;
  std::vector<Twist2> command_history;
  // A residual predictor's nominal model carried along those poses (learning/omni_residual.h).
  std::shared_ptr<const NominalTrackState> nominal;
};

// A copy of everything that changes inside a backend (see OmniBackend::Save).
struct OmniBackendState {
  std::vector<OmniRobotState> robots;
};

class OmniBackend {
 public:
  virtual ~OmniBackend() = default;
  virtual std::string name() const = 0;
  // The backend robot i runs on: name() but on a field of several (sim/grouped_omni_backend.h).
  virtual std::string robot_backend(int robot) const {
    static_cast<void>(robot);
    return name();
  }
  virtual int num_robots() const = 0;
  virtual const FrameTiming& timing() const = 0;

  // Puts robot i at `pose` moving at `velocity` (robot frame), its controller settled
  // on that velocity.
  virtual void Reset(int robot, const Pose2& pose, const Twist2& velocity) = 0;
  // Corrects robot i's current pose to a measurement, keeping its velocity (robot frame)
  // and everything internal (the controller's state; a learned backend keeps its older
  // poses, so a window corrected every frame holds measured poses).
  virtual void MoveBody(int robot, const Pose2& pose) = 0;
  // Moves robot i's body to `pose` by what no measurement saw (a slip drawn from the
  // driving noise), keeping the rest as MoveBody does. Only a backend that tells the two
  // apart overrides it: a residual predictor carried by its observer follows a push but
  // takes a measurement through its filter (learning/omni_residual.h).
  virtual void PushBody(int robot, const Pose2& pose) { MoveBody(robot, pose); }
  // True when SetVelocity works: the backend's state holds each body's velocity (the
  // Newtonian backends). A learned backend's velocity is its window of poses.
  virtual bool has_velocity_state() const { return false; }
  // Sets robot i's velocity (robot frame), keeping its pose and everything internal (the
  // controller's set-points and integrals, the effects' queues and lags): the state
  // observer's correction (estimation/omni_observer.h). Throws std::logic_error where
  // has_velocity_state() is false.
  virtual void SetVelocity(int robot, const Twist2& velocity) {
    static_cast<void>(robot);
    static_cast<void>(velocity);
    throw std::logic_error("backend " + name() + " holds no velocity state to set");
  }
  // Advances one camera frame; commands[i] is what robot i's firmware receives now.
  virtual void StepFrame(const std::vector<Twist2>& commands) = 0;

  virtual Pose2 pose(int robot) const = 0;
  virtual Twist2 velocity(int robot) const = 0;  // robot frame

  // Steps (a robot's frame, or a prediction's) on which a learned backend held its
  // predictor to the bounds of its training data, since construction (Save and Restore
  // leave it); 0 for physics.
  virtual long bounded_steps() const { return 0; }
  // Steps whose inputs a learned backend's predictor never saw the like of in training
  // (learning/omni_predictor.h, InputsSeen), counted the same way; 0 for physics.
  virtual long unseen_input_steps() const { return 0; }
  // A learned backend: how far beyond its predictor's training range the inputs of its
  // steps since the last call went at most (learning/omni_predictor.h, InputExcess: 1 is
  // the range's span), the count starting again; -1 where the backend does not measure it
  // (physics, a predictor without ranges). Save and Restore leave it.
  virtual double TakeInputExcess() { return -1; }
  // Physics: the engine's grip check since construction (engines/omni_engine.h;
  // only the analytic engine, which cannot slip, checks); empty for learned backends.
  virtual GripCheck grip() const { return {}; }

  // Moves the model's parameters to a draw from their own uncertainty, for everything
  // simulated until the next call; a null `rng` moves them back to the estimate. Only a
  // backend whose model carries that uncertainty overrides it (the learned backend with a
  // linear predictor that has its weights' directions or a network with an ensemble,
  // learning/omni_predictor.h); the others draw nothing. Returns whether the backend
  // draws. Save and Restore leave the draw.
  virtual bool DrawParameters(Rng* rng) {
    static_cast<void>(rng);
    return false;
  }

  // Saves and restores everything that changes: restoring a saved state and stepping
  // gives the same result as stepping from where it was saved.
  virtual OmniBackendState Save() const = 0;
  virtual void Restore(const OmniBackendState& state) = 0;
};

}  // namespace twinsim
