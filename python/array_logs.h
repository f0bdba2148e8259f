// NumPy arrays and Python values into twinsim's logs and predictors, checked as files
// are (python/array_logs.cc): what the module's simulations and command functions take.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/omni/omni_log.h"

namespace py = pybind11;

namespace twinsim {

// Any array NumPy can view as C-ordered float64 (one copy where it cannot).
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An omni log: a file path, or an (N, 7) array t,x,y,theta,vx_cmd,vy_cmd,omega_cmd
// (`name` stands for its path in messages).
OmniLog ToOmniLog(const py::handle& log, const std::string& name);
// An arm log: a file path, or a dict of arrays t (N), q, tau and optionally qd, qdd,
// qref (N x n each).
ArmLog ToArmLog(const py::handle& log, const std::string& name);
// One log or a list of them ("log[i]" in messages).
std::vector<OmniLog> ToOmniLogs(const py::handle& logs);
std::vector<ArmLog> ToArmLogs(const py::handle& logs);
// A new (rows, cols) float64 array.
Array NewArray(py::ssize_t rows, py::ssize_t cols);
// A predictor argument: None, a file path, or a loaded predictor.
std::shared_ptr<const OmniPredictor> OmniPredictorArg(const py::handle& p);
std::shared_ptr<const ArmPredictor> ArmPredictorArg(const py::handle& p);

}  // namespace twinsim
