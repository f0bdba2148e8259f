#include "serve/simulator_control.h"

#include <algorithm>
#include <cmath>

#include "serve/robot_control.h"

namespace twinsim {

Pose2 TeleportedPose(const RobotTeleport& t, const Pose2& current) {
  return Pose2{t.x.value_or(current.x), t.y.value_or(current.y), WrapAngle(t.theta.value_or(current.theta))};
}

BallState TeleportedBall(const BallTeleport& t, const BallState& current, double radius) {
  BallState b = current;
  if (t.x) b.position.x() = *t.x;
  if (t.y) b.position.y() = *t.y;
  b.position.z() = std::max(radius, t.z.value_or(radius));
  b.velocity = Eigen::Vector3d(t.vx.value_or(0), t.vy.value_or(0), t.vz.value_or(0));
  // Rolling: the spin that matches the velocity on the floor, w = z x v / r.
  b.spin = Eigen::Vector3d::Zero();
  if (t.roll) b.spin = Eigen::Vector3d(-b.velocity.y(), b.velocity.x(), 0) / radius;
  return b;
}

SimulatorCommandResult ReadSimulatorCommand(const std::string& bytes, const TeamRoster& roster, const FieldModel& field,
                                            bool has_ball) {
  SimulatorCommandResult result;
  SimulatorCommand command;
  if (!command.ParseFromString(bytes)) {
    AddError(&result.response, "TWINSIM_MALFORMED",
             "the datagram of " + std::to_string(bytes.size()) + " bytes is not a SimulatorCommand");
    return result;
  }
  result.parsed = true;
  auto refuse = [&](const std::string& code, const std::string& message) {
    ++result.refused;
    AddError(&result.response, code, message);
  };
  if (command.has_config()) refuse("TWINSIM_UNSUPPORTED", "simulator configuration is not supported; the scene file configures the field");
  if (!command.has_control()) return result;
  const SimulatorControl& control = command.control();
  if (control.has_teleport_ball()) {
    const TeleportBall& t = control.teleport_ball();
    BallTeleport ball;
    if (t.has_x()) ball.x = t.x();
    if (t.has_y()) ball.y = t.y();
    if (t.has_z()) ball.z = t.z();
    if (t.has_vx()) ball.vx = t.vx();
    if (t.has_vy()) ball.vy = t.vy();
    if (t.has_vz()) ball.vz = t.vz();
    ball.roll = t.roll();
    const Eigen::Vector3d v(ball.vx.value_or(0), ball.vy.value_or(0), ball.vz.value_or(0));
    const bool finite = std::isfinite(ball.x.value_or(0)) && std::isfinite(ball.y.value_or(0)) &&
                        std::isfinite(ball.z.value_or(0)) && v.allFinite();
    if (!has_ball) {
      refuse("TWINSIM_NO_BALL", "teleport_ball: the field has no ball (the scene has no `ball:`)");
    } else if (t.by_force()) {
      refuse("TWINSIM_UNSUPPORTED", "teleport_ball: moves by force are not supported yet");
    } else if (!finite || std::abs(ball.x.value_or(0)) >= field.length / 2 ||
               std::abs(ball.y.value_or(0)) >= field.width / 2 || ball.z.value_or(0) < 0 || ball.z.value_or(0) > 10 ||
               v.norm() > kMaxKickSpeed) {
      refuse("TWINSIM_BAD_VALUE", "teleport_ball: the place is not finite or outside the " +
                                      std::to_string(field.length) + " x " + std::to_string(field.width) +
                                      " m field (z in 0..10 m), or the velocity not finite or beyond " +
                                      std::to_string(kMaxKickSpeed) + " m/s");
    } else {
      result.ball = ball;
    }
  }
  if (control.has_simulation_speed()) {
    const double speed = control.simulation_speed();
    if (std::isfinite(speed) && speed >= 0.01 && speed <= 100) {
      result.simulation_speed = speed;
    } else {
      refuse("TWINSIM_BAD_VALUE", "simulation_speed " + std::to_string(speed) + " is not in 0.01..100");
    }
  }
  for (const TeleportRobot& t : control.teleport_robot()) {
    const bool yellow = t.id().team() == YELLOW;
    if (t.id().team() != YELLOW && t.id().team() != BLUE) {
      refuse("TWINSIM_UNKNOWN_ROBOT", "teleport_robot: the robot id names no team (blue or yellow)");
      continue;
    }
    const TeamColor team = yellow ? TeamColor::kYellow : TeamColor::kBlue;
    const std::string robot = std::string(TeamName(team)) + " robot " + std::to_string(t.id().id());
    const int index = roster.Find(team, t.id().id());
    if (index < 0) {
      refuse("TWINSIM_UNKNOWN_ROBOT", "teleport_robot: no " + robot + " on the field");
      continue;
    }
    if (t.has_present() && !t.present()) {
      refuse("TWINSIM_UNSUPPORTED", "teleport_robot " + robot + ": removing robots is not supported yet");
      continue;
    }
    if (t.by_force()) {
      refuse("TWINSIM_UNSUPPORTED", "teleport_robot " + robot + ": moves by force are not supported yet");
      continue;
    }
    RobotTeleport teleport;
    teleport.robot = index;
    if (t.has_x()) teleport.x = t.x();
    if (t.has_y()) teleport.y = t.y();
    if (t.has_orientation()) teleport.theta = t.orientation();
    teleport.field_velocity = Twist2{t.v_x(), t.v_y(), t.v_angular()};
    const bool finite = std::isfinite(teleport.x.value_or(0)) && std::isfinite(teleport.y.value_or(0)) &&
                        std::isfinite(teleport.theta.value_or(0)) && IsFinite(teleport.field_velocity);
    const bool inside = std::abs(teleport.x.value_or(0)) < field.length / 2 &&
                        std::abs(teleport.y.value_or(0)) < field.width / 2;
    const bool slow = std::hypot(teleport.field_velocity.vx, teleport.field_velocity.vy) <= kMaxCommandSpeed &&
                      std::abs(teleport.field_velocity.omega) <= kMaxCommandOmega;
    if (!finite || !inside || !slow) {
      refuse("TWINSIM_BAD_VALUE", "teleport_robot " + robot + ": the place is not finite or outside the " +
                                      std::to_string(field.length) + " x " + std::to_string(field.width) +
                                      " m field, or the velocity not finite or beyond the command limits");
      continue;
    }
    result.teleports.push_back(teleport);
  }
  return result;
}

}  // namespace twinsim
