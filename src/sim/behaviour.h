// What drives a robot: a CommandSource, asked once per camera frame for the command to
// send now (robot frame; vx, vy m/s, omega rad/s), given only what the observer has
// received by then, never the true pose. The loop (sim/omni_simulation.h) delivers the
// observations late, by the model's vision delay, as the off-field computer of a real
// game gets them.
#pragma once

#include <memory>
#include <vector>

#include "core/pose.h"
#include "sim/ball_command.h"

namespace twinsim {

inline constexpr int kObservationWindow = 32;

// One observation as delivered to the behaviour.
struct Observation {
  int frame = 0;      // camera frame it was captured in
  int delivered = 0;  // frame it reached the behaviour (its row in the log)
  double t = 0;       // s, capture time
  Pose2 pose;      // field frame, with the camera's noise
};

struct BehaviourInput {
  int frame = 0;  // the current frame (the command is sent now)
  double t = 0;   // s, now
  // The last kObservationWindow observations delivered for this robot, oldest first;
  // the newest is several frames old (the model's vision delay).
  const std::vector<Observation>* observations = nullptr;
};

class CommandSource {
 public:
  virtual ~CommandSource() = default;
  virtual Twist2 Command(const BehaviourInput& in) = 0;
  // What the robot does to the ball in the same frame (asked after Command, only on a
  // field with a ball); scripted velocity sources neither kick nor dribble.
  virtual BallCommand Ball(const BehaviourInput& /*in*/) { return {}; }
  virtual std::unique_ptr<CommandSource> Clone() const = 0;
};

}  // namespace twinsim
