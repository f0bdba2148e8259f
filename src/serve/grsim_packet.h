// grSim's own protocol (RoboCup-SSL/grSim, proto/grSim_*.proto), which many teams'
// software and reinforcement-learning kits speak instead of the league's simulation
// protocol: one grSim_Packet per datagram on one port for both teams (20011 in grSim),
// unanswered. A packet is read by translating it into the league's messages, which the
// served field then reads exactly as it reads them on its own ports (docs/serve.md
// "grSim's protocol"):
//
//   grSim_Commands (isteamyellow)    -> a RobotControl of that team, per robot command:
//     veltangent, velnormal, velangular  local velocity (m/s forward, m/s left, rad/s)
//     wheelsspeed with wheel1..wheel4    wheel velocity: rad/s of grSim's wheels 1-4 (at
//                                        60, 135, 225 and 300 deg: front left, back left,
//                                        back right, front right; positive turning the
//                                        robot counter-clockwise) times the robot's own
//                                        wheel radius, m/s at the rim
//     kickspeedx, kickspeedz             kick_speed |(x, z)| m/s, kick_angle atan2(z, x) deg
//     spinner                            dribbler_speed kGrSimSpinnerRpm (0 when off)
//   grSim_Replacement                -> a SimulatorCommand:
//     robots (x, y m; dir deg; turnon)   teleport_robot at rest; turnon false takes the
//                                        robot off the field (present: false), true puts
//                                        it back (present: true)
//     ball (x, y m; vx, vy m/s)          teleport_ball (a coordinate left out is kept; a
//                                        velocity left out is 0)
//
//   GrSimPacket read = ReadGrSimPacket(datagram, wheel_radius);
//   if (read.commands) Apply(ReadRobotControl(read.commands->SerializeAsString(), read.team, ...));
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "serve/team_roster.h"
#include "ssl_simulation_control.pb.h"
#include "ssl_simulation_robot_control.pb.h"

namespace twinsim {

// The dribbler's speed while grSim's `spinner` is on (grSim's spinner is on or off).
inline constexpr double kGrSimSpinnerRpm = 10000;

struct GrSimPacket {
  bool parsed = false;                          // false: not a grSim_Packet
  TeamColor team = TeamColor::kBlue;            // the commands' team
  std::optional<RobotControl> commands;         // the packet's grSim_Commands, translated
  std::optional<SimulatorCommand> replacement;  // its grSim_Replacement, translated
};

// Reads one datagram. `wheel_radius(team, id)` is robot id's wheel radius (m; 0 for an
// id the team does not have, whose command the RobotControl reader refuses). Never
// throws for any bytes (fuzz/serve_packet_fuzz.cc).
GrSimPacket ReadGrSimPacket(const std::string& bytes, const std::function<double(TeamColor, unsigned)>& wheel_radius);

}  // namespace twinsim
