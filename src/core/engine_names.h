// The names users give physics: each engine twinsim knows, built into this binary or
// not (AvailableOmniEngines and AvailableArmEngines list the built ones), and the
// backends a scene or sweep may name, the engines and the learned predictor. One list,
// so that the scene readers, the commands' option checks and the factories agree.
#pragma once

#include <string>
#include <vector>

namespace twinsim {

// "analytic", "ode", "bullet".
const std::vector<std::string>& KnownEngines();
// The engines, then "learned".
const std::vector<std::string>& KnownBackends();
// True when `name` is one of KnownEngines().
bool IsKnownEngine(const std::string& name);

}  // namespace twinsim
