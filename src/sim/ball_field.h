// The ball among the robots (docs/ball.md): a BallEngine (ODE or Bullet) stepped beside
// the robots' backend, with what the robots do to the ball on top: the kicker (flat and
// chip kicks), the dribbler's pull, and what the engines leave out, rolling resistance
// and air drag.
//
// The loop (sim/omni_simulation.h) steps the robots through a frame first and then the
// ball through the same frame, each robot's chassis moving in the ball's world from its
// pose at the frame's start to its pose at the end, at constant speed (one-way
// coupling: the ball never pushes a robot).
//
//   BallField field(ball_model, robot_models, field_model,
//                   MakeBallEngine("ode", ball_model, robot_models, field_model));
//   field.Reset(start);
//   field.StepFrame(poses_before, poses_after, commands, 1.0 / 60);
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "core/pose.h"
#include "engines/ball_engine.h"
#include "sim/ball_command.h"
#include "robots/omni/ball_model.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// A move of the ball by force under way (BallField::Pull).
struct BallPull {
  Eigen::Vector2d target = Eigen::Vector2d::Zero();  // m, on the floor, field frame
  double time_left = 0;                              // s before the pull gives up
};

// Everything that changes about the ball field.
struct BallFieldState {
  BallState ball;
  std::vector<bool> contact;  // per robot: the ball touches its dribbler (end of the last frame)
  std::optional<BallPull> pull;  // a move by force under way
};

// Where the ball is relative to a robot's flat front.
struct FrontContact {
  double gap = 0;       // m, from the ball's surface to the front plane (negative: pressed in)
  double lateral = 0;   // m, the ball's centre along the front, robot y
  bool on_front = false;  // the ball's centre lies within the front's width, on the floor
};

// The ball relative to the front of a robot at `pose` with model `robot`.
FrontContact BallAtFront(const BallModel& ball, const OmniModel& robot, const Pose2& pose, const BallState& state);

class BallField {
 public:
  // Within this gap of the front (m) the dribbler pulls the ball and the kicker reaches it.
  static constexpr double kReach = 0.01;
  // Within this gap (m) the ball counts as touching the dribbler (RobotFeedback).
  static constexpr double kTouch = 0.003;
  // The ball's steps are at most this long: a 6.5 m/s kick moves 5 mm per step.
  static constexpr double kMaxStep = 1.0 / 1200;  // s
  // A move by force (Pull): a critically damped spring of this natural frequency
  // towards the target in the floor's plane, whose pull asks for no more than
  // kPullSpeed and gives no more than kPullAccel; it lets go when the ball is within
  // kPullTolerance of the target slower than kPullStopSpeed, or after kPullTimeout.
  static constexpr double kPullFrequency = 1.5;    // Hz
  static constexpr double kPullSpeed = 2;          // m/s
  static constexpr double kPullAccel = 10;         // m/s^2
  static constexpr double kPullTolerance = 0.01;   // m
  static constexpr double kPullStopSpeed = 0.02;   // m/s
  static constexpr double kPullTimeout = 10;       // s

  // Throws std::invalid_argument for an invalid ball model or a null engine.
  BallField(const BallModel& ball, std::vector<OmniModel> robots, const FieldModel& field,
            std::unique_ptr<BallEngine> engine);

  const BallModel& model() const { return model_; }
  const std::string& engine_name() const { return engine_name_; }
  int num_robots() const { return static_cast<int>(robots_.size()); }

  // Puts the ball at `state` at once (contacts forgotten, a move by force ended).
  void Reset(const BallState& state);
  // Starts moving the ball by force towards `target` (m, field frame, on the floor): a
  // force through its centre on every step of the frames that follow (see kPullFrequency),
  // besides whatever else acts on it (robots, kicks, walls). Replaces a move under way.
  void Pull(const Eigen::Vector2d& target);
  const std::optional<BallPull>& pull() const { return state_.pull; }
  const BallState& ball() const { return state_.ball; }
  // Whether the ball touched robot i's dribbler at the end of the last frame.
  bool contact(int robot) const { return state_.contact.at(static_cast<std::size_t>(robot)); }
  // What robot `robot`'s kicker did in the last StepFrame: 0 nothing, 1 a flat kick, 2 a
  // chip (grSim's robot status; nothing after Reset or Restore).
  int kicked(int robot) const { return kicks_.empty() ? 0 : kicks_.at(static_cast<std::size_t>(robot)); }

  // Advances one frame of `frame_dt` s: robot i moves from `from[i]` to `to[i]` (field
  // frame) at constant speed and acts on the ball with `commands[i]` (already delayed).
  // Throws std::invalid_argument when the lists are not one per robot.
  void StepFrame(const std::vector<Pose2>& from, const std::vector<Pose2>& to, const std::vector<BallCommand>& commands,
                 double frame_dt);

  BallFieldState Save() const { return state_; }
  // Throws std::invalid_argument for a state of another field.
  void Restore(const BallFieldState& state);

 private:
  // Rolling resistance and drag on the ball for the next step of dt.
  void AddResistance(double dt);
  // The move by force's pull for the next step.
  void AddPull();

  BallModel model_;
  std::vector<OmniModel> robots_;
  std::unique_ptr<BallEngine> engine_;
  std::string engine_name_;
  BallFieldState state_;
  std::vector<int> kicks_;     // per robot, kicked() of the last frame (empty: none since a reset)
  double normal_gravity_ = 0;  // m/s^2, gravity across the floor
};

}  // namespace twinsim
