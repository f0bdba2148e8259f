// One number as text by a printf format ("%.3f", "%g", "%.2e"), for messages, tables and
// reports: std::string PrintfNumber("%.1f", 100 * share).
#pragma once

#include <string>

namespace twinsim {

// `format` holds exactly one double conversion; the text is cut at 63 characters.
std::string PrintfNumber(const char* format, double value);

}  // namespace twinsim
