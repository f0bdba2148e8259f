// Fuzzes the excitation trajectory reader (Fourier series YAML written by `excite`).
#include "fuzz_util.h"
#include "identification/fourier_trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader(
      [&] { twinsim::ParseFourierTrajectoryYaml(twinsim::fuzz::AsString(data, size), "excitation.yaml"); });
}
