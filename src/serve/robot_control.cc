#include "serve/robot_control.h"

#include <Eigen/Core>
#include <cmath>

#include "core/math_constants.h"

#include "ssl_simulation_robot_control.pb.h"

namespace twinsim {
namespace {

bool InLimits(const Twist2& v) {
  return IsFinite(v) && std::hypot(v.vx, v.vy) <= kMaxCommandSpeed && std::abs(v.omega) <= kMaxCommandOmega;
}

}  // namespace

Twist2 LocalVelocity(const RobotMove& move, double theta) {
  return move.global ? FieldToBody(move.velocity, theta) : move.velocity;
}

RobotControlResult ReadRobotControl(const std::string& bytes, TeamColor team, const TeamRoster& roster,
                                    const std::vector<bool>* ball_contact, const std::vector<bool>* present) {
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
    if (present && static_cast<std::size_t>(index) < present->size() && !(*present)[static_cast<std::size_t>(index)]) {
      ++result.refused;
      AddError(&result.response, "TWINSIM_NOT_PRESENT",
               robot + " is off the field; its command is not applied (a teleport with present: true adds it)");
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
        const MoveWheelVelocity& w = m.wheel_velocity();
        const Eigen::Vector4d rims(w.front_right(), w.back_right(), w.back_left(), w.front_left());
        const std::optional<ProtocolWheelMap>& map = roster.robot(index).wheels;
        if (!map) {
          AddError(&result.response, "TWINSIM_UNSUPPORTED",
                   robot + ": its wheels are not the protocol's four (one per quadrant); send local or global "
                           "velocity");
          ok = false;
        } else if (!rims.allFinite() || rims.cwiseAbs().maxCoeff() > kMaxCommandSpeed) {
          AddError(&result.response, "TWINSIM_BAD_VALUE",
                   robot + ": wheel velocities (" + std::to_string(rims[0]) + ", " + std::to_string(rims[1]) + ", " +
                       std::to_string(rims[2]) + ", " + std::to_string(rims[3]) + ") m/s are not finite or beyond " +
                       std::to_string(kMaxCommandSpeed) + " m/s");
          ok = false;
        } else {
          // The body velocity that best explains the four (least squares, as the robot's
          // own odometry would): the on-board controllers then track it.
          const Eigen::Vector3d v = *map * rims;
          move.velocity = Twist2{v[0], v[1], v[2]};
        }
      } else {
        // A move_command that names no velocity: refused, and said so.
        AddError(&result.response, "TWINSIM_BAD_VALUE",
                 robot + ": an empty move_command (it sets none of local_velocity, global_velocity, wheel_velocity)");
        ok = false;
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
    const bool asks_ball = (c.has_kick_speed() && c.kick_speed() != 0) || (c.has_dribbler_speed() && c.dribbler_speed() != 0);
    if (!ball_contact) {
      if (asks_ball)
        AddError(&result.response, "TWINSIM_NO_BALL", robot + ": kicks and the dribbler need a ball; the scene has none");
    } else {
      BallCommand ball;
      const double speed = c.kick_speed(), angle = c.kick_angle(), dribbler = c.dribbler_speed();
      if (!(std::isfinite(speed) && speed >= 0 && speed <= kMaxKickSpeed) ||
          !(std::isfinite(angle) && angle >= 0 && angle <= kMaxKickAngle)) {
        ++result.refused;
        AddError(&result.response, "TWINSIM_BAD_VALUE",
                 robot + ": kick_speed " + std::to_string(speed) + " m/s must lie in 0.." + std::to_string(kMaxKickSpeed) +
                     " and kick_angle " + std::to_string(angle) + " deg in 0.." + std::to_string(kMaxKickAngle));
      } else {
        ball.kick_speed = speed;
        ball.kick_angle = angle * kPi / 180;
      }
      if (!(std::isfinite(dribbler) && dribbler >= 0 && dribbler <= kMaxDribblerSpeed)) {
        ++result.refused;
        AddError(&result.response, "TWINSIM_BAD_VALUE",
                 robot + ": dribbler_speed " + std::to_string(dribbler) + " rpm must lie in 0.." +
                     std::to_string(kMaxDribblerSpeed));
      } else {
        ball.dribbler_speed = dribbler;
      }
      result.ball_commands.emplace_back(index, ball);
    }
    RobotFeedback* f = result.response.add_feedback();
    f->set_id(static_cast<unsigned>(roster.robot(index).id));
    f->set_dribbler_ball_contact(ball_contact && (*ball_contact)[static_cast<std::size_t>(index)]);
  }
  return result;
}

}  // namespace twinsim
