// serve's logs written frame by frame (scene/run_log_stream.h) are the files `run`
// writes for the same frames, byte for byte: lost observations, a robot taken off the
// field and the ball included.
#include "scene/run_log_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "core/error.h"
#include "io/output_files.h"
#include "scene/command_log.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

TEST(RunLogStream, TheStreamedFilesAreRunsFilesByteForByte) {
  const std::string d = testing::TempDir("run_log_stream");
  // omni4 with a camera that loses a fifth of the frames.
  std::string text = testing::ReadText(SourcePath("models/omni4.yaml"));
  const std::string keep = "drop_probability: 0.0";
  ASSERT_NE(text.find(keep), std::string::npos);
  text.replace(text.find(keep), keep.size(), "drop_probability: 0.2");
  const std::string model = testing::WriteText(d + "/omni4_lossy.yaml", text);
  const Scene scene = LoadSceneFromString(
      "name: stream\nbackend: analytic\nframe_rate: 60\nduration: 2\nseed: 4\n"
      "ball: {start: {x: 0.5, y: 0, vx: -1}}\nrobots:\n"
      "  - {name: a, model: " + model + ", start: {x: 0, y: 0}, commands: {type: random}}\n"
      "  - {name: b, model: " + model + ", start: {x: 1, y: 1}, commands: {type: figure_eight}}\n",
      "stream.yaml", ".");
  Simulation sim = MakeSimulation(scene, "analytic");
  RunLogStream stream(d + "/streamed", {"a", "b"}, /*ball=*/true, scene.frame_rate);
  // serve's way: written by a thread of the stream's own.
  RunLogStream background(d + "/background", {"a", "b"}, /*ball=*/true, scene.frame_rate, /*background=*/true);
  EXPECT_TRUE(stream.names().empty());
  EXPECT_FALSE(std::filesystem::exists(d + "/streamed")) << "nothing before the first frame";
  SimulationResult result;
  result.robot_names = {"a", "b"};
  result.timing = sim.backend().timing();
  result.frames.resize(2);
  int lost = 0;
  for (int k = 0; k < 120; ++k) {
    if (k == 50) sim.Remove(1);
    const std::vector<FrameRecord> records = sim.Step();
    stream.Append(records, &sim.ball_record());
    background.Append(records, &sim.ball_record());
    for (std::size_t i = 0; i < 2; ++i) result.frames[i].push_back(records[i]);
    result.ball.push_back(sim.ball_record());
    lost += records[0].observed ? 0 : 1;
  }
  EXPECT_GT(lost, 5) << "the test should cover lost observations";
  EXPECT_EQ(stream.frames(), 120);
  background.Finish();
  background.Finish();  // a second time: nothing
  OutputFiles files(d + "/whole");
  WriteOmniRunFiles(scene, result, /*plots=*/false, &files);
  files.Write("commands.csv", CommandsCsv(result));
  const std::vector<std::string> expected{"trajectory.csv", "truth.csv", "trajectory_b.csv", "truth_b.csv",
                                          "ball.csv", "commands.csv"};
  EXPECT_EQ(stream.names(), expected);
  for (const std::string& name : expected) {
    const std::string whole = testing::ReadText(d + "/whole/" + name);
    EXPECT_GT(whole.size(), 100u) << name;
    EXPECT_EQ(testing::ReadText(d + "/streamed/" + name), whole) << name;
    EXPECT_EQ(testing::ReadText(d + "/background/" + name), whole) << name;
  }
}

TEST(RunLogStream, AFileThatCannotBeCreatedIsNamed) {
  const std::string d = testing::TempDir("run_log_stream_bad");
  testing::WriteText(d + "/in_the_way", "a file where the folder should be");
  RunLogStream stream(d + "/in_the_way/out", {"a"}, false, 30);
  try {
    stream.Append({FrameRecord{}}, nullptr);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("in_the_way"), std::string::npos) << e.what();
  }
  EXPECT_THROW(stream.Append({FrameRecord{}, FrameRecord{}}, nullptr), std::invalid_argument);
  // Out of the way, the next frame creates the files, headers first.
  std::filesystem::remove(d + "/in_the_way");
  stream.Append({FrameRecord{}}, nullptr);
  EXPECT_EQ(testing::ReadText(d + "/in_the_way/out/trajectory.csv"), kOmniLogHeader);  // a frame not seen: no row
  const std::string commands = testing::ReadText(d + "/in_the_way/out/commands.csv");
  EXPECT_EQ(commands.rfind(kCommandsHeader, 0), 0u) << commands;
  EXPECT_EQ(std::count(commands.begin(), commands.end(), '\n'), 2) << commands;
}

// In the background the writer creates the files (serve's frame loop never waits for the
// file system): a folder that cannot be made comes back from Finish, named.
TEST(RunLogStream, ABackgroundFileThatCannotBeCreatedIsNamedByFinish) {
  const std::string d = testing::TempDir("run_log_stream_bad_background");
  testing::WriteText(d + "/in_the_way", "a file where the folder should be");
  RunLogStream stream(d + "/in_the_way/out", {"a"}, false, 30, /*background=*/true);
  try {
    stream.Append({FrameRecord{}}, nullptr);
    stream.Finish();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("in_the_way"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(d + "/in_the_way/out"));
}

// A write the system refuses on the background thread (a disk full: the trajectory
// file is /dev/full) comes back to the caller, naming the file: from an Append after it,
// or from Finish.
TEST(RunLogStream, ABackgroundWriteThatFailsIsNamed) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const std::string d = testing::TempDir("run_log_stream_full");
  std::filesystem::create_directories(d + "/out");
  std::filesystem::create_symlink("/dev/full", d + "/out/trajectory.csv");
  bool thrown = false;
  {
    RunLogStream stream(d + "/out", {"a"}, false, 30, /*background=*/true);
    try {
      for (int k = 0; k < 10000; ++k) stream.Append({FrameRecord{}}, nullptr);
      stream.Finish();
    } catch (const InputError& e) {
      thrown = true;
      EXPECT_NE(std::string(e.what()).find(d + "/out/trajectory.csv"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(thrown);
}

}  // namespace
}  // namespace twinsim
