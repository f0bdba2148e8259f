// Fuzzes the arm model reader for the project's YAML (DH table, inertia, friction, effects).
#include "fuzz_util.h"
#include "robots/arm/arm_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader(
      [&] { twinsim::LoadArmModelFromYamlString(twinsim::fuzz::AsString(data, size), "arm.yaml"); });
}
