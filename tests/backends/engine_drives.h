// Drives of one omni robot on an engine, for the tests that compare engines: a model
// without delay or camera noise, a run of a command spec, and how far two runs' true
// paths part.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "robots/omni/omni_model.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"

namespace twinsim::testing {

// `m` without delay and camera noise, for physics checks.
OmniModel Quiet(OmniModel m);

// Seed 000's test drive: from rest at 45 degrees to the heading, 1.5 m/s for 1.5 s from
// t = 0.2 s, then a hard stop.
CommandSpec TestDrive45();

// `seconds` of `spec` driving `model` from the origin on `backend` (physics at the
// default substeps of `frame_rate`), one robot, no walls in reach.
SimulationResult Drive(const std::string& backend, const OmniModel& model, const CommandSpec& spec, double seconds,
                       std::uint64_t seed = 1, double frame_rate = 30);

// The largest distance (m) and heading difference (rad, wrapped) between two runs' true
// poses, frame by frame.
std::pair<double, double> LargestTruthDifference(const SimulationResult& a, const SimulationResult& b);

}  // namespace twinsim::testing
