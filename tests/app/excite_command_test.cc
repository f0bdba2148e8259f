// `twinsim excite` as users and scripts see it: files, determinism, exit codes and
// messages.
#include <gtest/gtest.h>

#include <filesystem>

#include "identification/fourier_trajectory.h"
#include "io/csv_table.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::ReadText;
using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;
using testing::WriteText;
namespace fs = std::filesystem;

// A quick design: 3 harmonics of 0.5 Hz (a 2 s period), one short start.
const char* kQuick = " --harmonics 3 --fundamental 0.5 --samples 40 --starts 1 --iterations 15 --threads 1";

TEST(ExciteCommand, WritesTheExcitationAndItsReferenceDeterministically) {
  const std::string a = TempDir("excite_a"), b = TempDir("excite_b");
  const std::string model = SourcePath("models/rrr.yaml");
  auto r1 = RunTwinsim("excite --model " + model + " --out " + a + kQuick + " --periods 2");
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  EXPECT_NE(r1.out.find("condition number"), std::string::npos) << r1.out;
  EXPECT_NE(r1.out.find(a + "/excitation.yaml"), std::string::npos) << r1.out;
  auto r2 = RunTwinsim("excite --model " + model + " --out " + b + kQuick + " --periods 2 --quiet");
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(r2.out, "");
  for (const char* file : {"/excitation.yaml", "/reference.csv"}) EXPECT_EQ(ReadText(a + file), ReadText(b + file));
#ifdef TWINSIM_HAVE_OSMESA
  EXPECT_EQ(ReadText(a + "/excitation.png"), ReadText(b + "/excitation.png"));
#endif
  const FourierTrajectory t = LoadFourierTrajectory(a + "/excitation.yaml");
  EXPECT_EQ(t.harmonics(), 3);
  EXPECT_EQ(t.fundamental, 0.5);
  EXPECT_EQ(t.joint_names, (std::vector<std::string>{"waist", "shoulder", "elbow"}));
  const CsvTable csv = ReadCsvTable(a + "/reference.csv");
  EXPECT_EQ(csv.rows.size(), 4000u);  // 2 periods of 2 s at the model's 1 ms
  EXPECT_EQ(csv.header.size(), 16u);
  EXPECT_GE(csv.RequireColumn("tau3"), 0);
}

TEST(ExciteCommand, RunsBatchAdaptiveTrialsOnAPlant) {
  const std::string dir = TempDir("excite_plant");
  const std::string model = SourcePath("models/rrr.yaml");
  auto design = RunTwinsim("excite --model " + model + " --out " + dir + "/design" + kQuick + " --quiet");
  ASSERT_EQ(design.exit_code, 0) << design.err;
  auto r = RunTwinsim("excite --model " + model + " --out " + dir + "/adapt --trajectory " + dir +
                      "/design/excitation.yaml --plant " + SourcePath("tests/identification/rrr_plant.yaml") +
                      " --trials 3 --torque-noise 0.05");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Batch-adaptive estimation for rrr"), std::string::npos) << r.out;
  const CsvTable csv = ReadCsvTable(dir + "/adapt/adaptive.csv");
  EXPECT_GE(csv.rows.size(), 2u);
  EXPECT_LE(csv.rows.size(), 3u);
  // The excitation was used as given.
  EXPECT_EQ(ReadText(dir + "/adapt/excitation.yaml"), ReadText(dir + "/design/excitation.yaml"));
#ifdef TWINSIM_HAVE_OSMESA
  EXPECT_TRUE(fs::exists(dir + "/adapt/adaptive_parameters.png"));
  EXPECT_TRUE(fs::exists(dir + "/adapt/adaptive_tracking.png"));
#endif
}

TEST(ExciteCommand, BadInputIsExitTwoWithFileAndLine) {
  const std::string dir = TempDir("excite_bad");
  const std::string model = SourcePath("models/rrr.yaml");
  const std::string bad = WriteText(dir + "/bad.yaml", "fundamental_hz: 0.1\njoints:\n  - {q0: 0, a: [1, 2], b: [1]}\n");
  auto r = RunTwinsim("excite --model " + model + " --out " + dir + "/out --trajectory " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ":3:27: 'b' in 'joint 1': expected 2 numbers (as many as 'a'), got 1"), std::string::npos)
      << r.err;
  const std::string two = WriteText(dir + "/two.yaml", "fundamental_hz: 0.1\njoints:\n  - {q0: 0, a: [1], b: [1]}\n"
                                                       "  - {q0: 0, a: [1], b: [1]}\n");
  r = RunTwinsim("excite --model " + model + " --out " + dir + "/out --trajectory " + two);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(two + ": the trajectory has 2 joint(s) but model 'rrr' has 3"), std::string::npos) << r.err;
  r = RunTwinsim("excite --model " + model + " --out " + dir + "/out --acceleration-limit 10 20");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("acceleration limits: expected 3 values (one per joint of 'rrr'), got 2"), std::string::npos)
      << r.err;
  r = RunTwinsim("excite --model " + model + " --out " + dir + "/out --harmonics 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("excite: starting at rest needs at least 2 harmonics"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

}  // namespace
}  // namespace twinsim
