#include "serve/grsim_packet.h"

#include <cmath>

#include "core/math_constants.h"
#include "grSim_Packet.pb.h"

namespace twinsim {
namespace {

RobotCommand Translate(const grSim_Robot_Command& g, TeamColor team,
                       const std::function<double(TeamColor, unsigned)>& wheel_radius) {
  RobotCommand c;
  c.set_id(g.id());
  RobotMoveCommand* move = c.mutable_move_command();
  if (g.wheelsspeed()) {
    // grSim's wheels 1-4 sit at 60, 135, 225 and 300 deg from the heading.
    const double r = wheel_radius(team, g.id());
    MoveWheelVelocity* w = move->mutable_wheel_velocity();
    w->set_front_left(static_cast<float>(r * g.wheel1()));
    w->set_back_left(static_cast<float>(r * g.wheel2()));
    w->set_back_right(static_cast<float>(r * g.wheel3()));
    w->set_front_right(static_cast<float>(r * g.wheel4()));
  } else {
    MoveLocalVelocity* v = move->mutable_local_velocity();
    v->set_forward(g.veltangent());
    v->set_left(g.velnormal());
    v->set_angular(g.velangular());
  }
  const double x = g.kickspeedx(), z = g.kickspeedz();
  c.set_kick_speed(static_cast<float>(std::hypot(x, z)));
  c.set_kick_angle(x == 0 && z == 0 ? 0.0f : static_cast<float>(std::atan2(z, x) * 180 / kPi));
  c.set_dribbler_speed(g.spinner() ? static_cast<float>(kGrSimSpinnerRpm) : 0.0f);
  return c;
}

SimulatorCommand Translate(const grSim_Replacement& g) {
  SimulatorCommand command;
  SimulatorControl* control = command.mutable_control();
  for (const grSim_RobotReplacement& r : g.robots()) {
    TeleportRobot* t = control->add_teleport_robot();
    t->mutable_id()->set_id(r.id());
    t->mutable_id()->set_team(r.yellowteam() ? YELLOW : BLUE);
    t->set_x(static_cast<float>(r.x()));
    t->set_y(static_cast<float>(r.y()));
    t->set_orientation(static_cast<float>(r.dir() * kPi / 180));
    // grSim puts a replaced robot down at rest.
    t->set_v_x(0);
    t->set_v_y(0);
    t->set_v_angular(0);
    if (r.has_turnon()) t->set_present(r.turnon());
  }
  if (g.has_ball()) {
    const grSim_BallReplacement& b = g.ball();
    TeleportBall* t = control->mutable_teleport_ball();
    if (b.has_x()) t->set_x(static_cast<float>(b.x()));
    if (b.has_y()) t->set_y(static_cast<float>(b.y()));
    t->set_vx(static_cast<float>(b.vx()));
    t->set_vy(static_cast<float>(b.vy()));
  }
  return command;
}

}  // namespace

GrSimPacket ReadGrSimPacket(const std::string& bytes, const std::function<double(TeamColor, unsigned)>& wheel_radius) {
  GrSimPacket out;
  grSim_Packet packet;
  // Required fields left out (a grSim client always sets them) read as their defaults.
  if (!packet.ParsePartialFromString(bytes)) return out;
  out.parsed = true;
  if (packet.has_commands()) {
    const grSim_Commands& g = packet.commands();
    out.team = g.isteamyellow() ? TeamColor::kYellow : TeamColor::kBlue;
    out.commands.emplace();
    for (const grSim_Robot_Command& c : g.robot_commands())
      *out.commands->add_robot_commands() = Translate(c, out.team, wheel_radius);
  }
  if (packet.has_replacement()) out.replacement = Translate(packet.replacement());
  return out;
}

}  // namespace twinsim
