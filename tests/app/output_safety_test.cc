// Issue 14: nothing half-written. A command that fails part-way (a write that fails, as on
// a full disk, through TWINSIM_FAIL_WRITE) or is interrupted (SIGINT, SIGTERM) leaves no
// file under its final name; one that succeeds leaves all of them.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "robots/omni/omni_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;
using testing::RunTwinsim;
using testing::SourcePath;
using testing::TempDir;

// The paths a command listed under "wrote:", in order.
std::vector<std::string> WroteList(const std::string& out) {
  std::vector<std::string> paths;
  std::istringstream lines(out.substr(out.find("wrote:") == std::string::npos ? out.size() : out.find("wrote:")));
  std::string line;
  std::getline(lines, line);
  while (std::getline(lines, line) && line.rfind("  ", 0) == 0) paths.push_back(line.substr(2));
  return paths;
}

// Every regular file under `dir` (none when it does not exist).
std::vector<std::string> FilesUnder(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files.push_back(e.path().string());
  }
  return files;
}

struct FailCase {
  const char* name;
  // The command with {out} for its output folder and {d} for the case's folder.
  std::string args;
};

std::string FillPaths(std::string s, const std::string& key, const std::string& value) {
  for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + value.size()))
    s.replace(at, key.size(), value);
  return s;
}

class FailPartWay : public ::testing::TestWithParam<FailCase> {};

// Runs the command once to learn which files it writes, then again with the write of the
// last one failing: exit 2 and nothing under the output folder, not even the files written
// before the failure.
TEST_P(FailPartWay, LeavesNoFileBehind) {
  const FailCase& c = GetParam();
  const std::string d = TempDir(std::string("fail_") + c.name);
  const std::string log = d + "/log.csv";
  WriteOmniLog(log, testing::RecordLog(testing::Omni4(), testing::RandomDrive(1.5, 4, 1.5), 20, 7).rows);

  const std::string good = d + "/good";
  const auto ok = RunTwinsim(FillPaths(FillPaths(c.args, "{out}", good), "{d}", d));
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  // The files in the order written where the command lists them, else all it left.
  std::vector<std::string> wrote = WroteList(ok.out);
  if (wrote.empty()) {
    wrote = FilesUnder(good);
    std::sort(wrote.begin(), wrote.end());
  }
  ASSERT_GE(wrote.size(), 2u) << ok.out;
  for (const std::string& p : wrote) EXPECT_TRUE(fs::exists(p)) << p;

  const std::string last = fs::path(wrote.back()).filename().string();
  const std::string bad = d + "/bad";
  ::setenv("TWINSIM_FAIL_WRITE", last.c_str(), 1);
  const auto failed = RunTwinsim(FillPaths(FillPaths(c.args, "{out}", bad), "{d}", d));
  ::unsetenv("TWINSIM_FAIL_WRITE");
  EXPECT_EQ(failed.exit_code, 2) << failed.err;
  EXPECT_NE(failed.err.find(last), std::string::npos) << failed.err;
  EXPECT_TRUE(FilesUnder(bad).empty()) << "left behind: " << FilesUnder(bad).front();
  EXPECT_FALSE(fs::exists(bad)) << "the output folder it created stays only if something is in it";
}

INSTANTIATE_TEST_SUITE_P(
    Commands, FailPartWay,
    ::testing::Values(
        FailCase{"run", "run " + SourcePath("scenes/drive45.yaml") + " --backend analytic --out {out}"},
        FailCase{"compare", "compare --model " + SourcePath("models/omni4.yaml") +
                                " --log {d}/log.csv --backend analytic --out {out}"},
        FailCase{"excite", "excite --model " + SourcePath("models/rrr.yaml") +
                               " --out {out} --harmonics 3 --fundamental 0.5 --samples 40 --starts 1 --iterations 15"
                               " --threads 1 --periods 2"},
        FailCase{"ilc", "ilc " + SourcePath("scenes/rrr_writing_ilc.yaml") + " --out {out} --trials 2"},
        FailCase{"tune_pid", "tune-pid " + SourcePath("scenes/tune_pid_zeros.yaml") + " --out {out} --iterations 2"},
        FailCase{"diagnose", "diagnose --model " + SourcePath("models/omni4.yaml") +
                                 " --log {d}/log.csv --out {out} --max-effects 1"}),
    [](const ::testing::TestParamInfo<FailCase>& info) { return std::string(info.param.name); });

// Starts `twinsim ARGS` and sends `signal` after `delay`; returns the exit status.
int RunAndSignal(const std::string& args, int signal_number, std::chrono::milliseconds delay, std::string* err) {
  const std::string dir = TempDir("signal_cmd");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(TWINSIM_BINARY) + " " + args + " >" + dir + "/out 2>" + dir + "/err";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::this_thread::sleep_for(delay);
  ::kill(pid, signal_number);
  int status = 0;
  ::waitpid(pid, &status, 0);
  *err = testing::ReadText(dir + "/err");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// A scene long enough to be interrupted in the middle.
std::string LongScene(const std::string& dir) {
  std::string text = testing::ReadText(SourcePath("scenes/drive45.yaml"));
  text.replace(text.find("duration: 4.0"), 13, "duration: 20000");
  text.replace(text.find("../models/"), 10, SourcePath("models") + "/");
  return testing::WriteText(dir + "/long.yaml", text);
}

TEST(Interrupt, SigintStopsARunWithNoOutputAndExit130) {
  const std::string d = TempDir("sigint_run");
  std::string err;
  // ODE: a 20,000 s scene takes minutes, so the signal surely lands mid-run.
  const int code = RunAndSignal("run " + LongScene(d) + " --backend ode --out " + d + "/out", SIGINT,
                                std::chrono::milliseconds(1500), &err);
  EXPECT_EQ(code, 130) << err;
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;
  EXPECT_TRUE(FilesUnder(d + "/out").empty());
}

TEST(Interrupt, SigtermStopsABatchKeepingOnlyCompleteJobs) {
  const std::string d = TempDir("sigterm_batch");
  const std::string sweep = testing::WriteText(
      d + "/sweep.yaml", "name: long\nseed: 3\ncommand: run\nfixed:\n  scene: " + SourcePath("scenes/drive45.yaml") +
                             "\n  backend: ode\n  scene.duration: 200\n"
                             "grid:\n  scene.seed: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]\n");
  // 12 jobs of about 1 s each on ODE, two at a time: the signal lands mid-sweep.
  std::string err;
  const int code = RunAndSignal("batch " + sweep + " --out " + d + "/out --jobs 2", SIGTERM,
                                std::chrono::milliseconds(1500), &err);
  EXPECT_EQ(code, 143) << err;
  EXPECT_FALSE(fs::exists(d + "/out/summary.csv"));
  // Each job folder left is complete (its result.json is there) or gone.
  std::error_code ec;
  if (fs::exists(d + "/out/jobs", ec)) {
    for (const auto& job : fs::directory_iterator(d + "/out/jobs")) {
      EXPECT_TRUE(fs::exists(job.path() / "result.json")) << job.path();
    }
  }
  // --resume finishes the sweep.
  const auto resumed = RunTwinsim("batch " + sweep + " --out " + d + "/out --jobs 2 --resume");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_TRUE(fs::exists(d + "/out/summary.csv"));
}

}  // namespace
}  // namespace twinsim
