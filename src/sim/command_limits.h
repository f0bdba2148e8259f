// The largest commands a robot accepts from outside: `twinsim serve` refuses beyond
// them (serve/robot_control.h), and a command log (scene/command_log.h) holds nothing a
// team could not have sent. One home for both.
#pragma once

namespace twinsim {

inline constexpr double kMaxCommandSpeed = 20;    // m/s, a command beyond is refused
inline constexpr double kMaxCommandOmega = 100;   // rad/s
inline constexpr double kMaxKickSpeed = 20;       // m/s, a kick beyond is refused (the kicker clips at its own limit)
inline constexpr double kMaxKickAngle = 89;       // deg
inline constexpr double kMaxDribblerSpeed = 1e5;  // rpm

}  // namespace twinsim
