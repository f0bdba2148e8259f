// Implementation of test_util.h (named *_test.cc so the test glob picks it up).
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_util.h"

namespace twinsim::testing {

std::string SourcePath(const std::string& relative) { return std::string(TWINSIM_SOURCE_DIR) + "/" + relative; }

std::string TempDir(const std::string& name) {
  namespace fs = std::filesystem;
  fs::path p = fs::temp_directory_path() / ("twinsim_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

OmniModel Omni4() { return LoadOmniModel(SourcePath("models/omni4.yaml")); }
OmniModel Omni3() { return LoadOmniModel(SourcePath("models/omni3.yaml")); }

CommandResult RunTwinsim(const std::string& args) {
  const std::string dir = TempDir("cmd");
  const std::string cmd = std::string(TWINSIM_BINARY) + " " + args + " >" + dir + "/out 2>" + dir + "/err";
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadText(dir + "/out");
  r.err = ReadText(dir + "/err");
  return r;
}

}  // namespace twinsim::testing
