// The golden set: the shipped scenes, run on the analytic backend with their own seeds,
// still give the results kept under tests/golden/<scene>/ (`twinsim regress`, default
// tolerances). When a change is meant to move them, regenerate with
// scripts/update-golden and review the diff (docs/regression.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <set>

#include "test_util.h"

namespace twinsim {
namespace {

using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;
namespace fs = std::filesystem;

const char* const kGoldenScenes[] = {"drive45", "steps", "figure_eight"};

class Golden : public ::testing::TestWithParam<const char*> {};

TEST_P(Golden, RunMatchesTheGoldenSet) {
  const std::string scene = GetParam();
  std::string golden = SourcePath("tests/golden/" + scene);
  ASSERT_TRUE(fs::exists(golden + "/trajectory.csv")) << golden << ": run scripts/update-golden";
  const std::string candidate = TempDir("golden_" + scene);
  auto run = RunTwinsim("run " + SourcePath("scenes/" + scene + ".yaml") + " --backend analytic --out " + candidate +
                        " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.err;
#ifndef TWINSIM_HAVE_OSMESA
  // A build without OSMesa may not render plots: compare its trajectories only.
  bool has_png = false;
  for (const auto& e : fs::directory_iterator(candidate)) has_png |= e.path().extension() == ".png";
  if (!has_png) {
    const std::string csv_only = TempDir("golden_csv_" + scene);
    for (const auto& e : fs::directory_iterator(golden))
      if (e.path().extension() == ".csv") fs::copy_file(e.path(), csv_only + "/" + e.path().filename().string());
    golden = csv_only;
  }
#endif
  // The analytic paths do not move at all, so a plot that changed beyond 0.1 % of its
  // pixels changed on its own (a lost legend, a swapped colour): that regresses here.
  auto r = RunTwinsim("regress --golden " + golden + " --candidate " + candidate + " --pixel-tolerance 0.001");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err
                            << "\nIf this change is meant to move the golden set, run scripts/update-golden and "
                               "review the diff (docs/regression.md).";
  if (r.exit_code == 0) {
    EXPECT_NE(r.out.find("\nok: "), std::string::npos) << r.out;
  }
}

INSTANTIATE_TEST_SUITE_P(ShippedScenes, Golden, ::testing::ValuesIn(kGoldenScenes),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST(GoldenSet, EveryFolderIsAShippedSceneAndEverySceneHasAFolder) {
  std::set<std::string> folders;
  for (const auto& e : fs::directory_iterator(SourcePath("tests/golden")))
    if (e.is_directory()) folders.insert(e.path().filename().string());
  for (const char* scene : kGoldenScenes) EXPECT_TRUE(folders.count(scene)) << scene;
  for (const auto& f : folders) {
    EXPECT_TRUE(std::find(std::begin(kGoldenScenes), std::end(kGoldenScenes), f) != std::end(kGoldenScenes))
        << "tests/golden/" << f << " is not checked: add it to kGoldenScenes";
    EXPECT_TRUE(fs::exists(SourcePath("scenes/" + f + ".yaml"))) << "tests/golden/" << f << " has no scene";
    EXPECT_FALSE(fs::exists(SourcePath("tests/golden/" + f + "/regress"))) << "tests/golden/" << f << "/regress";
  }
}

}  // namespace
}  // namespace twinsim
