// Binds twinsim.OmniObserver into the Python module (python/observer_binding.cc).
#pragma once

#include <pybind11/functional.h>
#include <pybind11/pybind11.h>

#include <functional>

#include "robots/omni/omni_model.h"

namespace py = pybind11;

namespace twinsim {

// `model_of` turns the module's Python model object into an OmniModel.
void BindOmniObserver(py::module_& m, const std::function<OmniModel(const py::handle&)>& model_of);

}  // namespace twinsim
