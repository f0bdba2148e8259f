// The module's simulations (python/simulation_binding.cc): OmniSim, an omni scene stepped
// from Python through the same loop, delay line and camera as `twinsim run`, and ArmSim,
// an arm driven by torques (or its computed-torque controller) with the model's delay.
#pragma once

#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace twinsim {

// Binds OmniSim and ArmSim.
void BindSimulations(py::module_& m);

}  // namespace twinsim
