// Fuzzes the sweep reader. The input is placed in scenes/sweeps/ of a scratch folder whose
// scenes/ and models/ hold the shipped files, so that the paths a shipped sweep names
// resolve as they do in the source tree.
#include <filesystem>

#include "batch/sweep.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  static const fs::path root = [] {
    const char* tmp = std::getenv("TMPDIR");
    fs::path r = fs::path(tmp ? tmp : "/tmp") / ("twinsim_fuzz_sweep_" + std::to_string(::getpid()));
    fs::create_directories(r / "scenes" / "sweeps");
    std::error_code ec;
    for (const char* folder : {"models"}) fs::create_directory_symlink(fs::path(TWINSIM_SOURCE_DIR) / folder, r / folder, ec);
    for (const auto& e : fs::directory_iterator(fs::path(TWINSIM_SOURCE_DIR) / "scenes")) {
      if (e.is_regular_file()) fs::create_symlink(e.path(), r / "scenes" / e.path().filename(), ec);
    }
    return r;
  }();
  const fs::path path = root / "scenes" / "sweeps" / "input.yaml";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return twinsim::fuzz::RunReader([&] { twinsim::LoadSweep(path.string()); });
}
