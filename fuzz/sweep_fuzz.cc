// Fuzzes the sweep reader. The input is placed in scenes/sweeps/ of a scratch folder whose
// scenes/ and models/ hold the shipped files, so that the paths a shipped sweep names
// resolve as they do in the source tree.
#include <filesystem>

#include "batch/sweep.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  static const bool tree_made = [] {
    const fs::path r = twinsim::fuzz::ScratchDir() / "tree";
    fs::create_directories(r / "scenes" / "sweeps");
    std::error_code ec;
    fs::create_directory_symlink(fs::path(TWINSIM_SOURCE_DIR) / "models", r / "models", ec);
    for (const auto& e : fs::directory_iterator(fs::path(TWINSIM_SOURCE_DIR) / "scenes")) {
      if (e.is_regular_file()) fs::create_symlink(e.path(), r / "scenes" / e.path().filename(), ec);
    }
    return true;
  }();
  (void)tree_made;
  const std::string path = twinsim::fuzz::WriteInput(data, size, "tree/scenes/sweeps/input.yaml");
  return twinsim::fuzz::RunReader([&] { twinsim::LoadSweep(path); });
}
