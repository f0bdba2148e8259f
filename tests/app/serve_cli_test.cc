// `twinsim serve` as a user runs it: Ctrl-C stops it and it writes the contract's log.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "serve/udp_socket.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;
using testing::SourcePath;

// Starts `twinsim serve SCENE` on free ports with vision to `vision`, its output in
// DIR/stdout and DIR/stderr, and waits until vision flows (false: it never did).
bool StartServe(const std::string& scene, const std::string& d, const UdpSocket& vision, pid_t* pid) {
  const std::string args = "serve " + scene + " --out " + d + "/out --control-port 0 --blue-port 0 --yellow-port 0" +
                           " --vision-port " + std::to_string(vision.port());
  *pid = ::fork();
  if (*pid == 0) {
    const std::string cmd = "exec " + std::string(TWINSIM_BINARY) + " " + args + " >" + d + "/stdout 2>" + d + "/stderr";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool flowing = false;
  for (int i = 0; i < 100 && !flowing; ++i) flowing = WaitReadable({&vision}, 0.1) >= 0;
  return flowing;
}

TEST(ServeCli, SigintStopsAndWritesTheLogPerRobot) {
  const std::string d = testing::TempDir("serve_sigint");
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0.5, 0, 0]}]}";
  const std::string scene = testing::WriteText(
      d + "/s.yaml", "name: s\nbackend: analytic\nduration: 1\nrobots:\n  - {name: b0, model: " + model + ", " + hold +
                         "}\n  - {name: y0, team: yellow, model: " + model + ", start: {x: 1}, " + hold + "}\n");
  UdpSocket vision("127.0.0.1", 0);  // receives the packets, so none are refused by the host
  pid_t pid = 0;
  // Vision flows once the field runs; then stop it the way a user does.
  const bool flowing = StartServe(scene, d, vision, &pid);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string out = testing::ReadText(d + "/stdout"), err = testing::ReadText(d + "/stderr");
  EXPECT_TRUE(flowing) << err;
  ASSERT_TRUE(WIFEXITED(status)) << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << out << err;
  for (const char* name : {"trajectory.csv", "trajectory_y0.csv", "truth.csv", "truth_y0.csv", "commands.csv"})
    EXPECT_TRUE(fs::exists(d + "/out/" + name)) << name << "\n" << out << err;
  const std::string log = testing::ReadText(d + "/out/trajectory.csv");
  EXPECT_EQ(log.rfind("t,x,y,theta,vx_cmd,vy_cmd,omega_cmd", 0), 0u) << log.substr(0, 200);
  // About half a second at 30 fps, logged at simulated times; the scene's command drives b0.
  const auto rows = std::count(log.begin(), log.end(), '\n') - 1;
  EXPECT_GE(rows, 5) << log;
  EXPECT_NE(log.find(",0.5,0,0"), std::string::npos) << log.substr(0, 400);
  EXPECT_NE(out.find("frames"), std::string::npos) << out;
}

// The logs are written as the match runs: after a `kill -9` every file ends on a whole
// line, commands.csv holds no frame the others lack, and `run --commands` replays the
// match to the end of it, the observer's log a prefix of the served one.
TEST(ServeCli, AfterKill9TheLogsHoldEveryFinishedFrameAndReplay) {
  const std::string d = testing::TempDir("serve_kill9");
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string scene = testing::WriteText(
      d + "/s.yaml", "name: s\nbackend: analytic\nframe_rate: 60\nduration: 60\nseed: 3\nrobots:\n"
                     "  - {name: b0, model: " + model + ", commands: {type: random}}\n"
                     "  - {name: y0, team: yellow, model: " + model + ", start: {x: 1}, commands: {type: figure_eight}}\n");
  UdpSocket vision("127.0.0.1", 0);
  pid_t pid = 0;
  const bool flowing = StartServe(scene, d, vision, &pid);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(flowing) << testing::ReadText(d + "/stderr");
  ASSERT_TRUE(WIFSIGNALED(status));
  auto frames_in = [](const std::string& text) {
    EXPECT_FALSE(text.empty());
    EXPECT_EQ(text.back(), '\n') << "a file ends in the middle of a line";
    return std::count(text.begin(), text.end(), '\n') - 1;
  };
  const std::string commands = testing::ReadText(d + "/out/commands.csv");
  const auto command_rows = frames_in(commands);
  const auto truth_rows = frames_in(testing::ReadText(d + "/out/truth.csv"));
  frames_in(testing::ReadText(d + "/out/truth_y0.csv"));
  const std::string served = testing::ReadText(d + "/out/trajectory.csv");
  frames_in(served);
  // Two robots a frame; at most the frame cut by the kill is missing from commands.csv.
  ASSERT_EQ(command_rows % 2, 0) << commands.substr(commands.size() - 300);
  EXPECT_GE(truth_rows, 30);
  EXPECT_TRUE(command_rows / 2 == truth_rows || command_rows / 2 + 1 == truth_rows)
      << command_rows << " command rows, " << truth_rows << " truth rows";
  const testing::CommandResult replay =
      testing::RunTwinsim("run " + scene + " --commands " + d + "/out/commands.csv --out " + d + "/replay");
  ASSERT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  const std::string replayed = testing::ReadText(d + "/replay/trajectory.csv");
  EXPECT_GE(replayed.size(), 1000u);
  EXPECT_EQ(served.compare(0, replayed.size(), replayed), 0) << "the replay is not the served match";
}

// The robot list names each robot's backend; the logs are written as for one backend.
TEST(ServeCli, ItPrintsEachRobotsBackend) {
  const std::string d = testing::TempDir("serve_mixed");
  UdpSocket vision("127.0.0.1", 0);
  const testing::CommandResult r = testing::RunTwinsim(
      "serve " + SourcePath("scenes/serve_mixed.yaml") + " --frames 6 --out " + d +
      "/out --control-port 0 --blue-port 0 --yellow-port 0 --vision-port " + std::to_string(vision.port()));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("4 robot(s) on mixed: ode (blue0, blue1), analytic (yellow0, yellow1) at 60 fps"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("  blue 1: blue1 on ode\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  yellow 0: yellow0 on analytic\n"), std::string::npos) << r.out;
  for (const char* name : {"trajectory.csv", "trajectory_yellow1.csv", "ball.csv"})
    EXPECT_TRUE(fs::exists(d + "/out/" + name)) << name << "\n" << r.out << r.err;
}

TEST(ServeCli, BadOptionsExitWithCode2) {
  // Never a multicast group here: a multicast option on the default unicast address.
  testing::CommandResult r = testing::RunTwinsim("serve " + SourcePath("scenes/drive45.yaml") +
                                                 " --vision-ttl 4 --frames 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("multicast"), std::string::npos) << r.err;
  r = testing::RunTwinsim("serve " + SourcePath("scenes/drive45.yaml") + " --realtime-priority 200 --frames 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("0..99"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace twinsim
