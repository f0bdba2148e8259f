// A test log of the RRR arm recorded by ODE (another engine than the analytic one that
// the simulation score and compare use) under a PD with gravity feed-forward.
#pragma once

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim::testing {

// `seconds` of `plant` on ODE along a two-tone reference, the command updated every
// `hold` samples, one row per update (t, q, q̇, q̈, tau), read back through the CSV reader
// as "plant.csv".
ArmLog OdePdArmLog(const ArmModel& plant, double seconds, int hold);

}  // namespace twinsim::testing
