// Helpers shared by the tests: paths into the source tree, tiny inline models, and
// running the twinsim binary.
#pragma once

// Skips a rendering test in builds without OSMesa.
#ifdef TWINSIM_HAVE_OSMESA
#define SKIP_WITHOUT_OSMESA()
#else
#define SKIP_WITHOUT_OSMESA() GTEST_SKIP() << "built without OSMesa"
#endif

#include <cstdint>
#include <string>

#include "engines/omni_engine.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "scene/command_source.h"

namespace twinsim::testing {

// Absolute path of a file in the source tree ("models/omni4.yaml").
std::string SourcePath(const std::string& relative);
// A fresh, empty temporary folder for one test.
std::string TempDir(const std::string& name);
// Writes `text` to `path` and returns the path.
std::string WriteText(const std::string& path, const std::string& text);
std::string ReadText(const std::string& path);

// What LoadSceneFromString throws for `yaml` (named "s.yaml", paths relative to
// scenes/): the InputError's text, "" when it loads.
std::string SceneError(const std::string& yaml);

// The shipped four- and three-wheel models.
OmniModel Omni4();
OmniModel Omni3();

// Seeded random excitation; with a grip cap (m/s^2) and a leash (m) as in
// scenes/record_plant.yaml, or without (0).
CommandSpec RandomDrive(double max_speed, double max_centripetal, double leash);
// Drives `model` from the origin with `commands` for `seconds` on `backend` (30 fps) and
// returns what its observer logged, as if read from a file called `name`, on `field`.
OmniLog RecordLog(const OmniModel& model, const CommandSpec& commands, double seconds, std::uint64_t seed,
                  const std::string& backend = "analytic", const std::string& name = "recorded.csv",
                  const FieldModel& field = FieldModel{});

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};
// Runs build/twinsim with `args` (a shell-quoted string).
CommandResult RunTwinsim(const std::string& args);

}  // namespace twinsim::testing
