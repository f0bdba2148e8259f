// Fuzzes the PNG reader that `regress` uses on result folders.
#include "fuzz_util.h"
#include "io/png_image.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = twinsim::fuzz::WriteInput(data, size, "input.png");
  return twinsim::fuzz::RunReader([&] { twinsim::ReadPng(path); });
}
