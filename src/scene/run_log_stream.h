// A served match's logs written as it runs (twinsim serve): trajectory*.csv, truth*.csv,
// ball.csv and commands.csv, byte for byte the files `run` writes for the same frames
// (scene/scene_run.h, scene/command_log.h), each frame's lines appended to each file in
// one write (io/append_file.h). Memory stays flat however long the match runs, and
// after a crash or `kill -9` every file holds each frame that finished, whole:
// commands.csv is written last in a frame, so it never holds a frame the others lack,
// and `twinsim run SCENE --commands commands.csv` replays the match up to its end.
//
// With `background`, the writes happen on a thread of the stream's own, frame by frame
// in order: the caller (serve's frame loop) only formats the frame's lines and queues
// them, never waiting for the writer (a frame the writer's lock keeps out goes with the
// next), so a slow disk or a page-cache flush does not make a frame late. The queue
// holds at most kMaxQueuedFrames; beyond that Append waits for the disk (a log is never
// dropped). A write that fails is thrown by the next Append or by Finish(). After a
// `kill -9` the files hold each frame the thread wrote, whole, commands.csv last.
//
//   RunLogStream logs("out/match", {"b0", "y0"}, /*ball=*/true, 60, /*background=*/true);
//   field.SetFrameSink([&](const auto& records, const BallRecord* ball) { logs.Append(records, ball); });
//   ... field.Run(...) ...
//   logs.Finish();                       // every queued frame written (or the error thrown)
//   for (const std::string& name : logs.names()) files.Add(name);
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "io/append_file.h"
#include "sim/omni_simulation.h"

namespace twinsim {

class RunLogStream {
 public:
  static constexpr std::size_t kMaxQueuedFrames = 4096;
  static constexpr std::size_t kSpareFrames = 8;  // written frames' buffers kept for reuse

  // Nothing is created before the first frame (a field stopped before it writes nothing).
  RunLogStream(std::string folder, std::vector<std::string> robot_names, bool ball, double frame_rate,
               bool background = false);
  // Writes what is queued (errors are lost here: call Finish() to see them).
  ~RunLogStream();
  RunLogStream(const RunLogStream&) = delete;
  RunLogStream& operator=(const RunLogStream&) = delete;

  // Appends one frame: `records` per robot (as the robot names), the ball's (null
  // without a ball). The first frame creates the folder and the files (emptying those
  // of an earlier run), headers first: in the background, on the writer's thread. Throws
  // InputError naming a file that cannot be created or written (in the background, one
  // an earlier frame's write failed on), std::invalid_argument for records of another
  // number of robots.
  void Append(const std::vector<FrameRecord>& records, const BallRecord* ball);

  // Background: waits until every queued frame is written and stops the thread; throws
  // InputError naming the file a write failed on. Without a background thread: nothing.
  void Finish();

  // The files' names in the folder, in the order `run` lists them (empty before the
  // first frame).
  std::vector<std::string> names() const;
  long long frames() const { return frames_; }

 private:
  void Open();
  // Writes one frame's lines, file by file in order (commands.csv last).
  void Write(const std::vector<std::string>& lines);
  void WriterLoop();
  // Moves the frames the caller holds to the writer's queue (mutex_ held).
  void QueueHeld();

  std::string folder_;
  std::vector<std::string> robot_names_;
  bool ball_ = false;
  double frame_rate_ = 0;  // Hz
  long long frames_ = 0;
  // Per robot: trajectory, truth; then ball (with one) and commands. Touched only by
  // Write (the writer thread's, with one).
  std::vector<AppendFile> files_;
  std::vector<std::string> names_;
  std::vector<std::string> lines_;  // per file, the frame's lines (kept to reuse their memory)

  // The background writer: frames queued in order, spent buffers back for reuse.
  bool background_ = false;
  std::thread writer_;
  std::mutex mutex_;
  std::condition_variable wake_;  // the writer: a frame queued, or done
  std::condition_variable room_;  // the caller: the queue drained below its cap
  std::deque<std::vector<std::string>> queue_;
  std::vector<std::vector<std::string>> held_;  // the caller's: frames not queued yet (the writer held the queue)
  std::vector<std::vector<std::string>> spare_;
  bool done_ = false;
  std::string error_;  // the first write that failed ("" none)
};

}  // namespace twinsim
