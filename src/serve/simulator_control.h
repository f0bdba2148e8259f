// Reading the league's SimulatorCommand (ssl_simulation_control.proto), sent to the
// simulator control port, into teleports and a simulation speed, and the
// SimulatorResponse that answers it (error codes as in serve/robot_control.h, and
// TWINSIM_UNSUPPORTED for what the field cannot do yet: removing or adding robots,
// moves by force, configuration; TWINSIM_NO_BALL for a ball teleport on a field
// without a ball).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "engines/omni_engine.h"
#include "robots/omni/ball_model.h"
#include "serve/team_roster.h"
#include "ssl_simulation_control.pb.h"

namespace twinsim {

// Moves robot `robot` at once; a coordinate left out keeps the robot's current one.
struct RobotTeleport {
  int robot = 0;
  std::optional<double> x, y;   // m, field frame
  std::optional<double> theta;  // rad
  Twist2 field_velocity;        // m/s, m/s, rad/s in the field frame
};

// `current` is the robot's pose now; returns where the teleport puts it.
Pose2 TeleportedPose(const RobotTeleport& teleport, const Pose2& current);

// Moves the ball at once; a coordinate left out keeps the ball's current one.
struct BallTeleport {
  std::optional<double> x, y, z;     // m, field frame; z the centre's height (below the radius: on the floor)
  std::optional<double> vx, vy, vz;  // m/s
  bool roll = false;                 // true: spinning as it rolls (no slip); false: no spin
};

// Where the teleport puts a ball of `radius` that is at `current`.
BallState TeleportedBall(const BallTeleport& teleport, const BallState& current, double radius);

struct SimulatorCommandResult {
  bool parsed = false;                     // false: not a SimulatorCommand
  std::vector<RobotTeleport> teleports;    // the ones accepted
  std::optional<BallTeleport> ball;        // accepted
  std::optional<double> simulation_speed;  // > 0, real time x this
  int refused = 0;                         // requests refused
  SimulatorResponse response;
};

// Reads one datagram from the control port; teleports must land inside `field`'s
// walls. `has_ball`: the field has a ball (else a ball teleport is refused with
// TWINSIM_NO_BALL). Never throws for any bytes.
SimulatorCommandResult ReadSimulatorCommand(const std::string& bytes, const TeamRoster& roster, const FieldModel& field,
                                            bool has_ball = false);

}  // namespace twinsim
