// A scene's `plots:` list: parsed with defaults, checked with file:line, and drawn by
// `twinsim run` into the output folder.
#include "render/plot_spec.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "io/png_image.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

const char* kHead =
    "name: t\n"
    "duration: 1\n"
    "robots:\n"
    "  - model: ../models/omni4.yaml\n"
    "    commands: {type: test_drive}\n";

Scene Load(const std::string& plots) { return LoadSceneFromString(kHead + plots, "s.yaml", SourcePath("scenes")); }

std::string ErrorOf(const std::string& plots) {
  try {
    Load(plots);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PlotSpec, ParsesEveryKeyAndKeepsDefaults) {
  const Scene s = Load(
      "plots:\n"
      "  - {type: path, file: a.png}\n"
      "  - type: path\n"
      "    file: b-2_x.png\n"
      "    source: seen\n"
      "    width: 800\n"
      "    height: 600\n"
      "    region: [-1, 2, -0.5, 0.5]\n"
      "    orientation_every: 5\n"
      "    title: \"{scene} on {backend}, seed {seed}\"\n"
      "  - {type: path, file: c.png, region: field, orientation_every: 0}\n");
  ASSERT_EQ(s.plots.size(), 3u);
  const PlotSpec& a = s.plots[0];
  EXPECT_EQ(a.file, "a.png");
  EXPECT_EQ(a.source, "");
  EXPECT_EQ(a.width, 1200);
  EXPECT_EQ(a.height, 900);
  EXPECT_FALSE(a.region);
  EXPECT_EQ(a.orientation_every, -1);
  EXPECT_EQ(PlotTitle(a, "drive45", "ode", 1), "drive45 (ode)");
  const PlotSpec& b = s.plots[1];
  EXPECT_EQ(b.source, "seen");
  EXPECT_EQ(b.width, 800);
  ASSERT_TRUE(b.region);
  EXPECT_DOUBLE_EQ(b.region->x_min, -1);
  EXPECT_DOUBLE_EQ(b.region->y_max, 0.5);
  EXPECT_EQ(b.orientation_every, 5);
  EXPECT_EQ(PlotTitle(b, "t", "bullet", 7), "t on bullet, seed 7");
  EXPECT_TRUE(s.plots[2].region_is_field);
  EXPECT_EQ(s.plots[2].orientation_every, 0);
  EXPECT_TRUE(Load("").plots.empty());
}

TEST(PlotSpec, ProblemsAreReportedWithFileAndLine) {
  const std::string e = ErrorOf(
      "plots:\n"
      "  - {type: path, file: ../up.png, colour: red}\n"    // line 7
      "  - {type: pie, file: p.png}\n"                      // line 8
      "  - {type: path, file: dir/p.png}\n"                 // line 9
      "  - {type: path, file: p.jpg, width: 10}\n"          // line 10
      "  - {type: path, file: p.png, region: [1, 0, 0, 1]}\n"  // line 11
      "  - {type: path, file: p.png, source: model}\n"      // line 12
      "  - {type: path}\n");                                 // line 13
  EXPECT_NE(e.find("s.yaml:7:24: 'file' in 'plots[0]': expected a plain file name ending in .png"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:7:35: unknown key 'colour' in 'plots[0]' (known: "), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:8:12: 'type' in 'plots[1]': unknown value 'pie' (known: path)"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:9:24: 'file' in 'plots[2]': expected a plain file name"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:10:24: 'file' in 'plots[3]'"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:10:38: 'width' in 'plots[3]': must be in [240, 8192], got 10"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:11:39: 'region' in 'plots[4]': expected [x_min, x_max, y_min, y_max] with x_min < x_max"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("s.yaml:12:39: 'source' in 'plots[5]': unknown value 'model' (known: truth, seen, both)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("another plot already writes 'p.png'"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:13:5: missing required key 'file' in 'plots[6]'"), std::string::npos) << e;
  EXPECT_NE(ErrorOf("plots: {file: a.png}\n").find("s.yaml:6:8: 'plots': expected a list of plots"), std::string::npos);
}

TEST(PlotSpec, ShippedScenesAskForPathPlots) {
  for (const char* name : {"drive45", "figure_eight", "go_to_pose"}) {
    const Scene s = LoadScene(SourcePath(std::string("scenes/") + name + ".yaml"));
    ASSERT_EQ(s.plots.size(), 1u) << name;
    EXPECT_EQ(s.plots[0].file, "path.png");
  }
}

TEST(PlotSpec, RunWritesThePlotsAndListsThem) {
  const std::string a = testing::TempDir("plots_a"), b = testing::TempDir("plots_b");
  const std::string scene = SourcePath("scenes/drive45.yaml");
  auto r1 = testing::RunTwinsim("run " + scene + " --backend analytic --out " + a);
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  EXPECT_TRUE(std::filesystem::exists(a + "/trajectory.csv"));
  if (!RenderingCompiled()) {
    EXPECT_NE(r1.err.find("1 plot(s) not drawn: rendering not compiled; rebuild with -DTWINSIM_WITH_OSMESA=ON"),
              std::string::npos)
        << r1.err;
    EXPECT_FALSE(std::filesystem::exists(a + "/path.png"));
    GTEST_SKIP() << "built without OSMesa";
  }
  EXPECT_NE(r1.out.find("wrote:"), std::string::npos);
  EXPECT_NE(r1.out.find("  " + a + "/path.png\n"), std::string::npos) << r1.out;
  const RgbaImage image = ReadPng(a + "/path.png");
  EXPECT_EQ(image.width, 1200);
  EXPECT_EQ(image.height, 900);
  auto r2 = testing::RunTwinsim("run " + scene + " --backend analytic --quiet --out " + b);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(testing::ReadText(a + "/path.png"), testing::ReadText(b + "/path.png"));
}

}  // namespace
}  // namespace twinsim
