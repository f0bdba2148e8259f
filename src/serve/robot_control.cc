#include "serve/robot_control.h"

#include <cmath>

#include "ssl_simulation_robot_control.pb.h"

namespace twinsim {
namespace {

Team ProtocolTeam(TeamColor team) { return team == TeamColor::kBlue ? BLUE : YELLOW; }

bool InLimits(const Twist2& v) {
  return IsFinite(v) && std::hypot(v.vx, v.vy) <= kMaxCommandSpeed && std::abs(v.omega) <= kMaxCommandOmega;
}

}  // namespace

Twist2 LocalVelocity(const RobotMove& move, double theta) {
  return move.global ? FieldToBody(move.velocity, theta) : move.velocity;
}

RobotControlResult ReadRobotControl(const std::string& bytes, TeamColor team, const TeamRoster& roster) {
  RobotControlResult result;
  RobotControl control;
  if (!control.ParseFromString(bytes)) {
    AddError(&result.response, "TWINSIM_MALFORMED",
             "the datagram of " + std::to_string(bytes.size()) + " bytes is not a RobotControl");
    return result;
  }
  result.parsed = true;
  const std::string port = std::string(TeamName(team)) + " port";
  for (const RobotCommand& c : control.robot_commands()) {
    const std::string robot = std::string(TeamName(team)) + " robot " + std::to_string(c.id());
    const int index = roster.Find(team, c.id());
    if (index < 0) {
      ++result.refused;
      if (roster.Find(OtherTeam(team), c.id()) >= 0) {
        AddError(&result.response, "TWINSIM_OTHER_TEAM",
                 "robot " + std::to_string(c.id()) + " is a " + TeamName(OtherTeam(team)) +
                     " robot; the " + port + " commands only " + TeamName(team) + " robots");
      } else {
        AddError(&result.response, "TWINSIM_UNKNOWN_ROBOT", "no " + robot + " on the field");
      }
      continue;
    }
    if (c.has_move_command()) {
      const RobotMoveCommand& m = c.move_command();
      RobotMove move;
      bool ok = true;
      if (m.has_local_velocity()) {
        move.velocity = Twist2{m.local_velocity().forward(), m.local_velocity().left(), m.local_velocity().angular()};
      } else if (m.has_global_velocity()) {
        move.global = true;
        move.velocity = Twist2{m.global_velocity().vel_x(), m.global_velocity().vel_y(),
                               m.global_velocity().vel_angular()};
      } else if (m.has_wheel_velocity()) {
        SimulatorError* e = result.response.add_errors();
        e->set_code("TWINSIM_UNSUPPORTED");
        e->set_unsupported_capability(SIMULATOR_CAPABILITY_MOVE_WHEEL_VELOCITY);
        e->set_message(robot + ": wheel velocities are not supported yet; send local or global velocity");
        ok = false;
      } else {
        ok = false;  // an empty move command: nothing to do
      }
      if (ok && !InLimits(move.velocity)) {
        AddError(&result.response, "TWINSIM_BAD_VALUE",
                 robot + ": velocity (" + std::to_string(move.velocity.vx) + ", " + std::to_string(move.velocity.vy) +
                     ", " + std::to_string(move.velocity.omega) + ") is not finite or beyond " +
                     std::to_string(kMaxCommandSpeed) + " m/s, " + std::to_string(kMaxCommandOmega) + " rad/s");
        ok = false;
      }
      if (ok) {
        result.moves.emplace_back(index, move);
      } else {
        ++result.refused;
      }
    }
    if ((c.has_kick_speed() && c.kick_speed() != 0) || (c.has_dribbler_speed() && c.dribbler_speed() != 0)) {
      AddError(&result.response, "TWINSIM_NO_BALL", robot + ": kicks and the dribbler need a ball; the field has none yet");
    }
    RobotFeedback* f = result.response.add_feedback();
    f->mutable_id()->set_id(static_cast<unsigned>(roster.robot(index).id));
    f->mutable_id()->set_team(ProtocolTeam(team));
    f->set_dribbler_ball_contact(false);
  }
  return result;
}

}  // namespace twinsim
