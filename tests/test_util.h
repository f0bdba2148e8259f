// Helpers shared by the tests: paths into the source tree, tiny inline models, and
// running the twinsim binary.
#pragma once

#include <string>

#include "robots/omni/omni_model.h"

namespace twinsim::testing {

// Absolute path of a file in the source tree ("models/omni4.yaml").
std::string SourcePath(const std::string& relative);
// A fresh, empty temporary folder for one test.
std::string TempDir(const std::string& name);
// Writes `text` to `path` and returns the path.
std::string WriteText(const std::string& path, const std::string& text);
std::string ReadText(const std::string& path);

// The shipped four- and three-wheel models.
OmniModel Omni4();
OmniModel Omni3();

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};
// Runs build/twinsim with `args` (a shell-quoted string).
CommandResult RunTwinsim(const std::string& args);

}  // namespace twinsim::testing
