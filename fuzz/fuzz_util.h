// Shared by the libFuzzer targets: each target hands the fuzzer's bytes to one reader and
// accepts exactly one outcome besides success, InputError (exit 2, bad input). Any other
// exception escapes and aborts, which libFuzzer records as a crash, as it does a sanitizer
// report, a timeout or running out of memory.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace twinsim::fuzz {

inline std::string AsString(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A folder of this process's own under TMPDIR (made when first asked for), so that
// parallel fuzzing jobs do not share files.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::filesystem::path d = std::filesystem::path(tmp ? tmp : "/tmp") /
                              ("twinsim_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

// Writes the bytes to ScratchDir()/NAME and returns the path, for readers that only take
// a path.
inline std::string WriteInput(const uint8_t* data, size_t size, const std::string& name) {
  const std::filesystem::path path = ScratchDir() / name;
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data),
                                              static_cast<std::streamsize>(size));
  return path.string();
}

// Runs one reader; InputError is the expected answer to a bad input.
template <typename Reader>
int RunReader(Reader&& reader) {
  try {
    reader();
  } catch (const InputError&) {
  }
  return 0;
}

}  // namespace twinsim::fuzz
