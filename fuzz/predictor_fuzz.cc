// Fuzzes the predictor file readers, omni and arm (YAML with weights).
#include "fuzz_util.h"
#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = twinsim::fuzz::WriteInput(data, size, "input.pred");
  twinsim::fuzz::RunReader([&] { twinsim::OmniPredictor::Load(path); });
  return twinsim::fuzz::RunReader([&] { twinsim::ArmPredictor::Load(path); });
}
