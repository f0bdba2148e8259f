// Reading the league's RobotControl (ssl_simulation_robot_control.proto), sent by a
// team to its own port, into the moves the served field's robots receive, and the
// RobotControlResponse that answers it: one SimulatorError for every command refused,
// one RobotFeedback for every robot commanded.
//
// Error codes (SimulatorError.code) a client may act on:
//   TWINSIM_MALFORMED      the datagram is not a RobotControl
//   TWINSIM_OVERSIZED      the datagram is over the size limit (not read)
//   TWINSIM_UNKNOWN_ROBOT  the team has no robot of that id
//   TWINSIM_OTHER_TEAM     the id is the other team's robot, commanded from this port
//   TWINSIM_NOT_PRESENT    the robot is off the field (removed, or `present: false` in
//                          the scene): its command is not applied; a teleport with
//                          `present: true` adds it
//   TWINSIM_BAD_VALUE      a velocity that is not finite or beyond the limits below; a
//                          kick speed, kick angle or dribbler speed out of range (the
//                          move is still applied)
//   TWINSIM_UNSUPPORTED    wheel velocities for a robot whose wheels are not the
//                          protocol's four (a three-wheel robot, say)
//   TWINSIM_NO_BALL        a kick or the dribbler on a field without a ball (the scene
//                          has no `ball:`; the move is still applied)
//   TWINSIM_PORT_TAKEN     tournament mode: another address already drives this team
//   TWINSIM_TOURNAMENT     tournament mode: simulator control is refused
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/pose.h"
#include "serve/team_roster.h"
#include "sim/ball_field.h"
#include "sim/command_limits.h"
#include "ssl_simulation_robot_feedback.pb.h"

namespace twinsim {

// The limits: sim/command_limits.h (kMaxCommandSpeed, kMaxCommandOmega, kMaxKickSpeed,
// kMaxKickAngle in degrees, kMaxDribblerSpeed).

// A velocity command as the team sent it.
struct RobotMove {
  bool global = false;  // true: field frame (vx, vy along the field's axes)
  Twist2 velocity;      // robot frame unless global; m/s, m/s, rad/s
};

// The move in the robot's own frame for a robot heading `theta` (rad).
Twist2 LocalVelocity(const RobotMove& move, double theta);

struct RobotControlResult {
  bool parsed = false;                          // false: not a RobotControl
  std::vector<std::pair<int, RobotMove>> moves;  // (robot index, move), in the message's order
  // (robot index, kick and dribbler), for every robot commanded on a field with a ball
  // (absent values are 0), in the message's order.
  std::vector<std::pair<int, BallCommand>> ball_commands;
  int refused = 0;                               // robot commands refused
  RobotControlResponse response;
};

// An answer lists at most this many errors, then one TWINSIM_MORE_ERRORS counting the
// rest: a datagram of a few kB asking for thousands of errors gets a short answer (no
// amplification, nothing near the 64 kB a datagram can hold).
inline constexpr int kMaxErrorsPerAnswer = 16;
inline constexpr const char* kMoreErrors = "TWINSIM_MORE_ERRORS";

// Adds a SimulatorError with `code` and `message` to `errors` of any response, or counts
// it in the last entry once kMaxErrorsPerAnswer are listed ("... and N more errors").
template <typename Response>
void AddError(Response* response, const std::string& code, const std::string& message) {
  if (response->errors_size() < kMaxErrorsPerAnswer) {
    SimulatorError* e = response->add_errors();
    e->set_code(code);
    e->set_message(message);
    return;
  }
  int more = 0;
  if (response->errors_size() == kMaxErrorsPerAnswer) {
    response->add_errors()->set_code(kMoreErrors);
  } else {
    more = std::stoi(response->errors(kMaxErrorsPerAnswer).message().substr(8));  // after "... and "
  }
  ++more;
  response->mutable_errors(kMaxErrorsPerAnswer)
      ->set_message("... and " + std::to_string(more) + (more == 1 ? " more error" : " more errors") +
                    ", not listed (the first " + std::to_string(kMaxErrorsPerAnswer) + " are)");
}

// Reads one datagram from `team`'s port. `ball_contact` (per robot index: the ball
// touches its dribbler) is the field's ball; null: the field has none, kicks and the
// dribbler are refused with TWINSIM_NO_BALL. `present` (per robot index: on the field;
// null: all are): a command for a robot off the field is refused with
// TWINSIM_NOT_PRESENT and has no feedback. Never throws for any bytes.
RobotControlResult ReadRobotControl(const std::string& bytes, TeamColor team, const TeamRoster& roster,
                                    const std::vector<bool>* ball_contact = nullptr,
                                    const std::vector<bool>* present = nullptr);

}  // namespace twinsim
