// Fuzzes the scene readers, omni and arm, with the shipped models/ at hand so that scenes
// naming them get past the model reference into the rest of the checks.
#include "fuzz_util.h"
#include "scene/arm_scene.h"
#include "scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text = twinsim::fuzz::AsString(data, size);
  const std::string base = TWINSIM_SOURCE_DIR "/scenes";
  twinsim::fuzz::RunReader([&] { twinsim::LoadSceneFromString(text, "scene.yaml", base); });
  return twinsim::fuzz::RunReader([&] { twinsim::LoadArmSceneFromString(text, "scene.yaml", base); });
}
