#include "core/error.h"

namespace twinsim {

std::string SourceLocation::Prefix() const {
  std::string out;
  if (!path.empty()) out += path + ":";
  if (line > 0) out += std::to_string(line) + ":";
  if (line > 0 && column > 0) out += std::to_string(column) + ":";
  if (!out.empty()) out += " ";
  return out;
}

void ErrorList::ThrowIfAny() const {
  if (messages_.empty()) return;
  std::string all;
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    if (i) all += "\n";
    all += messages_[i];
  }
  throw InputError(all);
}

}  // namespace twinsim
