// Implementation of test_util.h (named *_test.cc so the test glob picks it up).
#include <sys/wait.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim::testing {

std::string SourcePath(const std::string& relative) { return std::string(TWINSIM_SOURCE_DIR) + "/" + relative; }

namespace {

// This process's folder of temporary folders.
std::filesystem::path ProcessTempRoot() {
  return std::filesystem::temp_directory_path() / ("twinsim_test_" + std::to_string(::getpid()));
}

// Removes the process's temporary folders when every test passed (a failure keeps them
// to look at, as does TWINSIM_KEEP_TEST_FILES=1): every ctest test is a process of its
// own, and a suite's run left a thousand folders (and the bad-input battery's 60 MB URDF)
// in /tmp.
class TempRootCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    const char* keep = std::getenv("TWINSIM_KEEP_TEST_FILES");
    if ((keep && *keep && std::string(keep) != "0") || !::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    std::filesystem::remove_all(ProcessTempRoot(), ignored);
  }
};

[[maybe_unused]] ::testing::Environment* const g_temp_root_cleanup =
    ::testing::AddGlobalTestEnvironment(new TempRootCleanup);

}  // namespace

std::string TempDir(const std::string& name) {
  namespace fs = std::filesystem;
  fs::path p = ProcessTempRoot() / name;
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

std::string SceneError(const std::string& yaml) {
  try {
    LoadSceneFromString(yaml, "s.yaml", SourcePath("scenes"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

OmniModel Omni4() { return LoadOmniModel(SourcePath("models/omni4.yaml")); }
OmniModel Omni3() { return LoadOmniModel(SourcePath("models/omni3.yaml")); }

CommandSpec RandomDrive(double max_speed, double max_centripetal, double leash) {
  CommandSpec spec;
  spec.type = "random";
  spec.max_speed = max_speed;
  spec.max_centripetal = max_centripetal;
  spec.leash = leash;
  return spec;
}

OmniLog RecordLog(const OmniModel& model, const CommandSpec& commands, double seconds, std::uint64_t seed,
                  const std::string& backend, const std::string& name, const FieldModel& field) {
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{}, MakeCommandSource(commands, seed, 0, seconds, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend(backend, {model}, field, FrameTiming{}), seed);
  const SimulationResult r = sim.Run(static_cast<int>(seconds * 30) + 1);
  return ParseOmniLog(FormatOmniLog(ObserverLog(r.frames[0])), name);
}

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
