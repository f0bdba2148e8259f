// The camera's noise in an omni robot's log, seen from the log alone: the noise floor
// of a 4-frame prediction's error (what a perfect model would still miss), which the
// identification and the diagnosis judge their models against.
#pragma once

#include <vector>

#include "robots/omni/omni_log.h"

namespace twinsim {

// The metric's noise floor (m): what a perfect model's 4-frame prediction error would
// be from the camera's noise alone, estimated from third differences of the poses over
// four consecutive frames that each hold a new measurement. *var_xy (m^2, per
// coordinate) and *var_theta (rad^2) receive the camera's variances where given.
double OmniNoiseFloor(const std::vector<OmniLog>& logs, double radius, double* var_xy = nullptr,
                      double* var_theta = nullptr);

}  // namespace twinsim
