// Fuzzes the omni model reader (YAML, docs/models.md).
#include "fuzz_util.h"
#include "robots/omni/omni_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader(
      [&] { twinsim::LoadOmniModelFromString(twinsim::fuzz::AsString(data, size), "omni.yaml"); });
}
