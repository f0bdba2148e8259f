// Unwrapping a phase response: std::arg gives each line's phase in (-180, 180] degrees,
// so a phase that keeps falling jumps by a whole turn where it crosses -180. Unwrapping
// adds whole turns (360 degrees) from the second line on so that each step from one
// line to the next lies within half a turn; the first line keeps its value. This is how
// a Bode plot's phase is drawn as one continuous curve.
//
//   std::vector<double> phase = UnwrapDegrees({170, -170, -150});  // 170, 190, 210
#pragma once

#include <vector>

namespace twinsim {

// `phase` (deg) with whole turns added so that successive values differ by at most
// 180 degrees; the first value is kept.
std::vector<double> UnwrapDegrees(const std::vector<double>& phase);

}  // namespace twinsim
