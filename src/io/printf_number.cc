#include "io/printf_number.h"

#include <cstdio>

namespace twinsim {

std::string PrintfNumber(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

}  // namespace twinsim
