// Numbers for the YAML files twinsim writes (models): the shortest text that reads back
// as the same double, so a written model loads bit for bit.
#pragma once

#include <string>

namespace twinsim {

// "0.089", not "0.088999999999999996"; "0" for both zeros.
std::string YamlNumber(double v);

}  // namespace twinsim
