// A served match's logs written as it runs (twinsim serve): trajectory*.csv, truth*.csv,
// ball.csv and commands.csv, byte for byte the files `run` writes for the same frames
// (scene/scene_run.h, scene/command_log.h), each frame's lines appended to each file in
// one write (io/append_file.h). Memory stays flat however long the match runs, and
// after a crash or `kill -9` every file holds each frame that finished, whole:
// commands.csv is written last in a frame, so it never holds a frame the others lack,
// and `twinsim run SCENE --commands commands.csv` replays the match up to its end.
//
//   RunLogStream logs("out/match", {"b0", "y0"}, /*ball=*/true, 60);
//   field.SetFrameSink([&](const auto& records, const BallRecord* ball) { logs.Append(records, ball); });
//   for (const std::string& name : logs.names()) files.Add(name);
#pragma once

#include <string>
#include <vector>

#include "io/append_file.h"
#include "sim/omni_simulation.h"

namespace twinsim {

class RunLogStream {
 public:
  // Nothing is created before the first frame (a field stopped before it writes nothing).
  RunLogStream(std::string folder, std::vector<std::string> robot_names, bool ball, double frame_rate);

  // Appends one frame: `records` per robot (as the robot names), the ball's (null
  // without a ball). The first call creates the folder and the files (emptying those of
  // an earlier run), headers first. Throws InputError naming a file that cannot be
  // created or written, std::invalid_argument for records of another number of robots.
  void Append(const std::vector<FrameRecord>& records, const BallRecord* ball);

  // The files' names in the folder, in the order `run` lists them (empty before the
  // first frame).
  std::vector<std::string> names() const;
  long long frames() const { return frames_; }

 private:
  void Open();

  std::string folder_;
  std::vector<std::string> robot_names_;
  bool ball_ = false;
  double frame_rate_ = 0;  // Hz
  long long frames_ = 0;
  // Per robot: trajectory, truth; then ball (with one) and commands.
  std::vector<AppendFile> files_;
  std::vector<std::string> names_;
  std::vector<std::string> lines_;  // per file, the frame's lines (kept to reuse their memory)
};

}  // namespace twinsim
