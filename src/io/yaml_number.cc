#include "io/yaml_number.h"

#include <cstdio>
#include <cstdlib>

namespace twinsim {

std::string YamlNumber(double v) {
  if (v == 0) return "0";
  char buf[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace twinsim
