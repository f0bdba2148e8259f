// Mathematical constants, for every layer (use these, not the non-standard M_PI).
//
//   const double w = 2 * kPi * frequency;  // rad/s from Hz
#pragma once

namespace twinsim {

// pi, the same double as M_PI and std::numbers::pi.
inline constexpr double kPi = 3.14159265358979323846;

}  // namespace twinsim
