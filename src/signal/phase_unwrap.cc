#include "signal/phase_unwrap.h"

namespace twinsim {

std::vector<double> UnwrapDegrees(const std::vector<double>& phase) {
  std::vector<double> out;
  out.reserve(phase.size());
  // The offset only ever grows by whole turns, so a slow drift is followed however far it goes.
  double offset = 0, previous = 0;
  for (std::size_t i = 0; i < phase.size(); ++i) {
    if (i > 0) {
      while (phase[i] + offset - previous > 180) offset -= 360;
      while (phase[i] + offset - previous < -180) offset += 360;
    }
    previous = phase[i] + offset;
    out.push_back(previous);
  }
  return out;
}

}  // namespace twinsim
