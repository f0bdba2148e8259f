#include "batch/batch_runner.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "batch/sweep.h"
#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;
using testing::ReadText;
using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;
using testing::WriteText;

// Every file under `dir` by relative path, with result.json's wall time and
// summary.csv's wall_s column (the only numbers that differ between runs) blanked.
std::map<std::string, std::string> Files(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), dir).string();
    std::string text = ReadText(e.path().string());
    std::stringstream in(text), out;
    std::string line;
    int wall_column = -1;
    while (std::getline(in, line)) {
      if (rel.size() >= 11 && rel.substr(rel.size() - 11) == "result.json" && line.find("\"wall_s\"") != std::string::npos)
        line = "wall";
      if (rel == "summary.csv") {
        std::vector<std::string> cells;
        std::stringstream row(line);
        std::string cell;
        while (std::getline(row, cell, ',')) cells.push_back(cell);
        if (wall_column < 0) {
          for (std::size_t i = 0; i < cells.size(); ++i)
            if (cells[i] == "wall_s") wall_column = static_cast<int>(i);
        } else if (wall_column < static_cast<int>(cells.size())) {
          cells[wall_column] = "wall";
        }
        line.clear();
        for (const std::string& c : cells) line += c + ",";
      }
      out << line << "\n";
    }
    files[rel] = out.str();
  }
  return files;
}

// Six short drives: two backends, three random chassis masses, one mass out of range.
std::string WriteSweep(const std::string& dir, const std::string& extra = "", const std::string& name = "t") {
  return WriteText(dir + "/sweep.yaml", "name: " + name + "\nseed: 3\nfixed:\n  scene: " + SourcePath("scenes/drive45.yaml") +
                                            "\n  scene.duration: 1\ngrid:\n  backend: [analytic, ode]\n"
                                            "  plant.chassis.mass: [2.0, 2.6, -1]\n" + extra);
}

BatchSummary RunSweep(const std::string& sweep, const std::string& out, int jobs, bool resume = false) {
  BatchOptions options;
  options.out = out;
  options.jobs = jobs;
  options.resume = resume;
  options.progress = false;
  return RunBatch(LoadSweep(sweep), options);
}

TEST(BatchRunner, OneAndTwoThreadsWriteTheSameBytesAndAFailingJobIsARow) {
  const std::string dir = TempDir("batch_threads");
  const std::string sweep = WriteSweep(dir);
  const BatchSummary one = RunSweep(sweep, dir + "/one", 1);
  const BatchSummary two = RunSweep(sweep, dir + "/two", 2);
  EXPECT_EQ(one.jobs, 6);
  EXPECT_EQ(one.ran, 6);
  EXPECT_EQ(one.failed, 2);  // the negative mass, on both backends
  EXPECT_EQ(two.threads, 2);
  const auto a = Files(dir + "/one");
  const auto b = Files(dir + "/two");
  EXPECT_EQ(a, b);
  ASSERT_TRUE(a.count("jobs/0000/trajectory.csv"));
  ASSERT_TRUE(a.count("jobs/0000/truth.csv"));
  const std::string csv = ReadText(dir + "/one/summary.csv");
  std::stringstream rows(csv);
  std::string header, row0, row2;
  std::getline(rows, header);
  std::getline(rows, row0);
  std::getline(rows, row0);
  std::getline(rows, row2);
  EXPECT_EQ(header.substr(0, header.find(",wall_s")), "job,seed,backend,plant.chassis.mass,status");
  EXPECT_NE(header.find(",final_x,final_y,final_theta,path_length,error"), std::string::npos);
  EXPECT_NE(row2.find(",-1,failed,"), std::string::npos) << row2;
  EXPECT_NE(row2.find("'mass' in 'chassis': must be positive"), std::string::npos) << row2;
  EXPECT_NE(row0.find(",ok,"), std::string::npos) << row0;
  EXPECT_TRUE(fs::exists(dir + "/one/summary.html"));
}

TEST(BatchRunner, ResumingAnInterruptedSweepEndsAsAnUninterruptedOne) {
  const std::string dir = TempDir("batch_resume");
  const std::string sweep = WriteSweep(dir);
  RunSweep(sweep, dir + "/whole", 2);
  // An interrupted run: two jobs never finished (no result.json), one left half a file.
  RunSweep(sweep, dir + "/cut", 2);
  fs::remove(dir + "/cut/summary.csv");
  fs::remove(dir + "/cut/summary.html");
  fs::remove(dir + "/cut/jobs/0001/result.json");
  fs::remove_all(dir + "/cut/jobs/0004");
  fs::remove(dir + "/cut/jobs/0003/result.json");
  WriteText(dir + "/cut/jobs/0003/trajectory.csv", "t,x,y,th");
  WriteText(dir + "/cut/jobs/0003/stray.tmp", "partial");
  const BatchSummary resumed = RunSweep(sweep, dir + "/cut", 1, /*resume=*/true);
  EXPECT_EQ(resumed.resumed, 3);
  EXPECT_EQ(resumed.ran, 3);
  EXPECT_EQ(Files(dir + "/whole"), Files(dir + "/cut"));
  // Resuming a complete sweep runs nothing.
  EXPECT_EQ(RunSweep(sweep, dir + "/cut", 1, true).ran, 0);
}

TEST(BatchRunner, AFolderHoldingASweepIsNotOverwritten) {
  const std::string dir = TempDir("batch_refuse");
  const std::string sweep = WriteSweep(dir);
  RunSweep(sweep, dir + "/out", 2);
  try {
    RunSweep(sweep, dir + "/out", 2);
    FAIL() << "ran over an existing sweep";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/out: already holds a sweep; add --resume to continue it, or choose "
                                           "another --out");
  }
  const std::string changed = WriteSweep(dir + "/changed", "  seed: [1, 2]\n");
  EXPECT_THROW(RunSweep(changed, dir + "/out", 2, true), InputError);
}

// batch.json holds the sweep's name as a JSON string: quotes and backslashes escaped, so
// the record parses and --resume recognises its own sweep.
TEST(BatchRunner, TheRecordOfASweepNamedWithQuotesIsJson) {
  const std::string dir = TempDir("batch_quoted");
  const std::string name = R"(say "hi" \ now)";
  const std::string sweep = WriteSweep(dir, "", "'" + name + "'");
  RunSweep(sweep, dir + "/out", 1);
  const nlohmann::json record = nlohmann::json::parse(ReadText(dir + "/out/batch.json"));
  EXPECT_EQ(record.at("sweep").get<std::string>(), name);
  EXPECT_EQ(record.at("jobs").get<int>(), 6);
  EXPECT_NO_THROW(RunSweep(sweep, dir + "/out", 1, true));
}

TEST(BatchRunner, ReplayJobsRecordTheirLogFirstForOmniAndArm) {
  const std::string dir = TempDir("batch_replay");
  const std::string omni = WriteText(
      dir + "/omni.yaml", "command: replay\nfixed:\n  scene: " + SourcePath("scenes/record_slipping_plant.yaml") +
                              "\n  scene.duration: 4\n  model: " + SourcePath("models/omni4.yaml") +
                              "\n  backend: analytic\ngrid:\n  plant.effects.traction_limit.a_max: [0.8, 3.0]\n");
  RunSweep(omni, dir + "/omni", 2);
  const std::string csv = ReadText(dir + "/omni/summary.csv");
  EXPECT_NE(csv.find("position_rmse,heading_rmse,predicted"), std::string::npos) << csv;
  EXPECT_TRUE(fs::exists(dir + "/omni/jobs/0000/trajectory.csv"));
  EXPECT_TRUE(fs::exists(dir + "/omni/jobs/0000/replay.csv"));
  // The nominal model predicts the grippier plant better: the hidden limit shows.
  std::stringstream rows(csv);
  std::string line;
  std::getline(rows, line);
  std::vector<double> rmse;
  while (std::getline(rows, line)) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    std::string cell;
    while (std::getline(row, cell, ',')) cells.push_back(cell);
    ASSERT_EQ(cells[3], "ok") << line;
    rmse.push_back(std::stod(cells[5]));
  }
  ASSERT_EQ(rmse.size(), 2u);
  EXPECT_GT(rmse[0], 2 * rmse[1]);

  const std::string arm = WriteText(
      dir + "/arm.yaml", "command: replay\nfixed:\n  scene: " + SourcePath("scenes/rrr_writing.yaml") +
                             "\n  model: " + SourcePath("models/rrr.yaml") +
                             "\n  plant.effects: [{name: payload, joint: null, mass: 0.1, x: 0.35}]\n"
                             "grid:\n  plant.effects.0.mass: [0.1, 1.0]\n");
  RunSweep(arm, dir + "/arm", 2);
  const std::string arm_csv = ReadText(dir + "/arm/summary.csv");
  EXPECT_NE(arm_csv.find("torque_error_rms_1,torque_relative_1"), std::string::npos) << arm_csv;
  EXPECT_EQ(arm_csv.find("failed"), std::string::npos) << arm_csv;
}

TEST(BatchCli, BadSweepsExitTwoWithFileAndLineAndAFirstJobThatDoesNotLoadToo) {
  const std::string dir = TempDir("batch_cli");
  const std::string bad = WriteText(dir + "/bad.yaml", "grid:\n  backend: [ode]\n  colour: [red]\n");
  auto r = RunTwinsim("batch " + bad + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ":3:3: unknown parameter 'colour'"), std::string::npos) << r.err;
  const std::string misspelt = WriteText(
      dir + "/misspelt.yaml", "fixed:\n  scene: " + SourcePath("scenes/drive45.yaml") + "\n  plant.chassis.mas: 2\n");
  r = RunTwinsim("batch " + misspelt + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(misspelt + ":3:3: job 0000 (the first) does not load"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown key 'mas'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
  EXPECT_EQ(RunTwinsim("batch " + misspelt + " --out " + dir + "/out --jobs -1").exit_code, 2);
}

// The same sweep under `mpirun -np 2` and on threads: the same bytes.
TEST(BatchMpi, TwoRanksWriteWhatThreadsWrite) {
  if (!MpiCompiled()) GTEST_SKIP() << "built without MPI";
  if (std::system("command -v mpirun >/dev/null 2>&1") != 0) GTEST_SKIP() << "no mpirun";
  const std::string dir = TempDir("batch_mpi");
  const std::string sweep = WriteSweep(dir);
  RunSweep(sweep, dir + "/threads", 2);
  const std::string cmd = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
                          "mpirun -np 2 --oversubscribe " + std::string(TWINSIM_BINARY) + " batch " + sweep +
                          " --out " + dir + "/mpi --jobs 1 --quiet >" + dir + "/log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadText(dir + "/log");
  EXPECT_EQ(Files(dir + "/threads"), Files(dir + "/mpi"));
  EXPECT_NE(ReadText(dir + "/mpi/summary.csv").find(",failed,"), std::string::npos);
}

}  // namespace
}  // namespace twinsim
