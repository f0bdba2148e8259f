// Fuzzes the arm model reader for URDF (through urdfdom).
#include "fuzz_util.h"
#include "robots/arm/arm_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader(
      [&] { twinsim::LoadArmModelFromUrdfString(twinsim::fuzz::AsString(data, size), "arm.urdf"); });
}
