// Reading the league's SimulatorCommand (ssl_simulation_control.proto), sent to the
// simulator control port, into teleports (at once or by force, robots added and
// removed), a simulation speed and configuration changes, and the SimulatorResponse
// that answers it (error codes as in serve/robot_control.h; TWINSIM_NOT_PRESENT for a
// teleport or move by force of a robot off the field without `present: true`;
// TWINSIM_UNSUPPORTED for configuration the field cannot change live, naming the field;
// TWINSIM_NO_BALL for a ball teleport on a field without a ball).
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

// Moves robot `robot` at once (or by force); a coordinate left out keeps the robot's
// current one (for a robot being added: its scene start's).
struct RobotTeleport {
  int robot = 0;
  std::optional<double> x, y;   // m, field frame
  std::optional<double> theta;  // rad
  Twist2 field_velocity;        // m/s, m/s, rad/s in the field frame (not for by_force)
  // Set: the robot is added (true; a robot on the field is teleported) or removed
  // (false; the rest of the teleport is ignored).
  std::optional<bool> present;
  bool by_force = false;        // moved there physically (Simulation::PullRobot)
};

// `current` is the robot's pose now; returns where the teleport puts it.
Pose2 TeleportedPose(const RobotTeleport& teleport, const Pose2& current);

// Moves the ball at once; a coordinate left out keeps the ball's current one.
struct BallTeleport {
  std::optional<double> x, y, z;     // m, field frame; z the centre's height (below the radius: on the floor)
  std::optional<double> vx, vy, vz;  // m/s
  bool roll = false;                 // true: spinning as it rolls (no slip); false: no spin
  bool by_force = false;             // moved to (x, y) physically (BallField::Pull); z, velocities ignored
  bool safely = false;               // robots in the way at (x, y) are moved out of it first
};

// Configuration changed live (SimulatorCommand.config).
struct ConfigChange {
  std::optional<int> vision_port;             // vision goes to this port from now on
  std::optional<double> robot_noise_xy;       // m, every robot's camera noise (stddev_robot_p)
  std::optional<double> robot_noise_theta;    // rad (stddev_robot_phi)
  std::optional<double> ball_noise_xy;        // m, the ball's camera noise on x and y (stddev_ball_p)
  std::optional<double> ball_drop;            // probability the camera misses the ball (missing_ball_detections)
};

// Where the teleport puts a ball of `radius` that is at `current`.
BallState TeleportedBall(const BallTeleport& teleport, const BallState& current, double radius);

struct SimulatorCommandResult {
  bool parsed = false;                     // false: not a SimulatorCommand
  std::vector<RobotTeleport> teleports;    // the ones accepted
  std::optional<BallTeleport> ball;        // accepted
  std::optional<double> simulation_speed;  // > 0, real time x this
  ConfigChange config;                     // accepted parts of a configuration
  int refused = 0;                         // requests refused
  SimulatorResponse response;
};

// Reads one datagram from the control port; teleports must land inside `field`'s
// walls. `has_ball`: the field has a ball (else a ball teleport is refused with
// TWINSIM_NO_BALL). `present` (per robot index: on the field; null: all are) decides
// which teleports need `present: true`; teleports in one message see the robots the
// earlier ones added or removed. Never throws for any bytes.
SimulatorCommandResult ReadSimulatorCommand(const std::string& bytes, const TeamRoster& roster, const FieldModel& field,
                                            bool has_ball = false, const std::vector<bool>* present = nullptr);

}  // namespace twinsim
