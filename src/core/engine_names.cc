#include "core/engine_names.h"

#include <algorithm>

namespace twinsim {

const std::vector<std::string>& KnownEngines() {
  static const std::vector<std::string> names = {"analytic", "ode", "bullet"};
  return names;
}

const std::vector<std::string>& KnownBackends() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> backends = KnownEngines();
    backends.push_back("learned");
    return backends;
  }();
  return names;
}

bool IsKnownEngine(const std::string& name) {
  const std::vector<std::string>& engines = KnownEngines();
  return std::find(engines.begin(), engines.end(), name) != engines.end();
}

}  // namespace twinsim
