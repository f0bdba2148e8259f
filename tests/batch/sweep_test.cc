#include "batch/sweep.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;
using testing::TempDir;
using testing::WriteText;

std::string Header() { return "scene: " + SourcePath("scenes/drive45.yaml") + "\n"; }

std::string LoadError(const std::string& path) {
  try {
    LoadSweep(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Sweep, GridTimesDrawsInOrderWithTheFirstAxisSlowest) {
  const std::string dir = TempDir("sweep_grid");
  const std::string path = WriteText(dir + "/s.yaml", "name: g\nseed: 9\nfixed:\n  " + Header() +
                                                          "grid:\n  backend: [analytic, ode]\n"
                                                          "  scene.duration: [1, 2, 3]\n"
                                                          "random:\n  draws: 2\n  parameters:\n"
                                                          "    plant.chassis.mass: {uniform: [2, 3]}\n");
  const Sweep sweep = LoadSweep(path);
  ASSERT_EQ(sweep.num_jobs(), 12);
  EXPECT_EQ(sweep.swept(), (std::vector<std::string>{"backend", "scene.duration", "plant.chassis.mass"}));
  const std::vector<SweepJob> jobs = ExpandSweep(sweep);
  ASSERT_EQ(jobs.size(), 12u);
  EXPECT_EQ(jobs[0].id, "0000");
  EXPECT_EQ(jobs[11].id, "0011");
  // Jobs 0-5 on analytic, 6-11 on ode; the duration changes every two jobs (the draws).
  EXPECT_EQ(jobs[5].Find("backend")->text, "analytic");
  EXPECT_EQ(jobs[6].Find("backend")->text, "ode");
  EXPECT_EQ(jobs[0].Find("scene.duration")->text, "1");
  EXPECT_EQ(jobs[1].Find("scene.duration")->text, "1");
  EXPECT_EQ(jobs[2].Find("scene.duration")->text, "2");
  EXPECT_EQ(jobs[7].Find("scene.duration")->text, "1");
  // Draws within range, different between jobs, and the same on every expansion.
  const std::vector<SweepJob> again = ExpandSweep(sweep);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const double m = std::stod(jobs[i].Find("plant.chassis.mass")->text);
    EXPECT_GE(m, 2.0);
    EXPECT_LE(m, 3.0);
    EXPECT_EQ(jobs[i].Find("plant.chassis.mass")->text, again[i].Find("plant.chassis.mass")->text);
    EXPECT_EQ(jobs[i].seed, again[i].seed);
  }
  EXPECT_NE(jobs[0].Find("plant.chassis.mass")->text, jobs[1].Find("plant.chassis.mass")->text);
  EXPECT_NE(jobs[0].seed, jobs[1].seed);
  // Another sweep seed draws other values.
  Sweep other = sweep;
  other.seed = 10;
  EXPECT_NE(ExpandSweep(other)[0].Find("plant.chassis.mass")->text, jobs[0].Find("plant.chassis.mass")->text);
}

TEST(Sweep, ASweptSeedIsTheJobsSeed) {
  const std::string dir = TempDir("sweep_seed");
  const std::string path = WriteText(dir + "/s.yaml", "fixed:\n  " + Header() + "grid:\n  seed: [4, 5, 6]\n");
  const std::vector<SweepJob> jobs = ExpandSweep(LoadSweep(path));
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].seed, 4u);
  EXPECT_EQ(jobs[2].seed, 6u);
}

TEST(Sweep, ExtendsKeepsPathsRelativeToTheFileThatNamesThem) {
  const std::string dir = TempDir("sweep_extends");
  std::filesystem::create_directories(dir + "/base");
  WriteText(dir + "/base/scene_link.yaml", "unused: 1\n");
  WriteText(dir + "/base/base.yaml", "name: base\ncommand: run\nfixed:\n  scene: scene_link.yaml\n"
                                     "grid:\n  backend: [ode, analytic]\n");
  const std::string path = WriteText(dir + "/child.yaml", "extends: base/base.yaml\nname: child\n"
                                                          "grid:\n  backend: [bullet]\n  seed: [1, 2]\n");
  const Sweep sweep = LoadSweep(path);
  EXPECT_EQ(sweep.name, "child");
  ASSERT_EQ(sweep.num_jobs(), 2);  // the child's backend axis replaced the base's
  const std::vector<SweepJob> jobs = ExpandSweep(sweep);
  EXPECT_EQ(jobs[0].Find("scene")->node.Scalar(), dir + "/base/scene_link.yaml");
  EXPECT_EQ(jobs[1].Find("backend")->text, "bullet");
}

TEST(Sweep, BadFilesGiveFileLineAndColumn) {
  const std::string dir = TempDir("sweep_bad");
  EXPECT_EQ(LoadError(WriteText(dir + "/a.yaml", "fixed:\n  " + Header() + "grid:\n  bakend: [ode]\n")),
            dir + "/a.yaml:4:3: unknown parameter 'bakend' (known: scene, model, log, predictor, backend, backends, "
                  "horizon, seed, and keys set in the files as scene.KEY, plant.KEY, model.KEY)");
  EXPECT_EQ(LoadError(WriteText(dir + "/b.yaml", "fixed:\n  scene: nowhere.yaml\n")),
            dir + "/b.yaml:2:10: parameter 'scene': no file '" + dir + "/nowhere.yaml'");
  EXPECT_EQ(LoadError(WriteText(dir + "/c.yaml", "fixed:\n  " + Header() + "grid:\n  backend: ode\n")),
            dir + "/c.yaml:4:12: grid parameter 'backend': expected a non-empty list of values");
  EXPECT_EQ(LoadError(WriteText(dir + "/d.yaml", "fixed:\n  " + Header() +
                                                      "random:\n  draws: 2\n  parameters:\n    plant.chassis.mass: "
                                                      "{gauss: [1, 2]}\n")),
            dir + "/d.yaml:6:26: 'random.parameters.plant.chassis.mass': unknown distribution 'gauss' (known: "
                  "uniform, log_uniform, integer, choice)");
  EXPECT_EQ(LoadError(WriteText(dir + "/e.yaml", "command: replay\nfixed:\n  " + Header())),
            dir + "/e.yaml: command replay: every job needs a model");
  EXPECT_EQ(LoadError(WriteText(dir + "/f.yaml", "comand: run\n")),
            dir + "/f.yaml:1:1: unknown key 'comand' (known: command, extends, fixed, grid, name, plots, random, "
                  "seed)");
  // A sweep of more than a million jobs is refused before anything is expanded.
  std::string big = "fixed:\n  " + Header() + "grid:\n";
  for (const char* axis : {"scene.a", "scene.b", "scene.c"}) {
    big += std::string("  ") + axis + ": [";
    for (int i = 0; i < 101; ++i) big += (i ? ", " : "") + std::to_string(i);
    big += "]\n";
  }
  EXPECT_NE(LoadError(WriteText(dir + "/g.yaml", big)).find("holds 1030301 jobs or more; at most 1000000"),
            std::string::npos);
}

}  // namespace
}  // namespace twinsim
