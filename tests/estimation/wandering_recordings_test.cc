// The wandering plant's recordings as log files, for studies run through the command
// line (docs/benchmarks.md, "identify's last digits again"): not a test of its own, so
// disabled; run with TWINSIM_STUDY_DIR=DIR build/twinsim_tests
// --gtest_also_run_disabled_tests --gtest_filter='WanderingRecordings.*'
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "estimation/wandering_plant.h"
#include "robots/omni/omni_log.h"

namespace twinsim {
namespace {

// The robot of tests/diagnosis/omni_foreign_diagnosis_test.cc as it was identified: a
// 40 s recording (seed 4) to fit, 60 s (seed 9) to validate, and 30 s recordings of
// seeds 5 to 8 (the unchanged robot the diagnosis compares its changes with), or to N
// with TWINSIM_STUDY_SEEDS=N (clean logs for the diagnosis's false-alarm count).
TEST(WanderingRecordings, DISABLED_WriteForStudies) {
  const char* dir = std::getenv("TWINSIM_STUDY_DIR");
  if (dir == nullptr) GTEST_SKIP() << "TWINSIM_STUDY_DIR names no directory";
  testing::WanderingPlant plant;
  plant.noise_sd = {0.05, 0.05, 0.3};
  plant.camera_theta = 0.005;
  const auto write = [&](const std::string& name, double seconds, std::uint64_t seed) {
    WriteOmniLog(std::string(dir) + "/" + name, testing::RecordWanderingPlant(plant, seconds, seed).log.rows);
  };
  write("foreign_fit_40s.csv", 40, 4);
  write("foreign_validation_60s.csv", 60, 9);
  const char* last = std::getenv("TWINSIM_STUDY_SEEDS");
  for (int seed = 5; seed <= (last ? std::atoi(last) : 8); ++seed) write("unchanged_30s_seed" + std::to_string(seed) + ".csv", 30, seed);
}

}  // namespace
}  // namespace twinsim
