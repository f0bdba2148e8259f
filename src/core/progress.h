// A progress line for long jobs on a terminal: "label [#####.....] 45% 2.3 s", redrawn
// at most ten times a second on stderr, and only when stderr is a terminal and the job
// has run for more than a second. Silent otherwise, so logs and pipes stay clean.
#pragma once

#include <chrono>
#include <string>

namespace twinsim {

class Progress {
 public:
  explicit Progress(std::string label, bool enabled = true);
  ~Progress();
  // Reports `done` of `total` units; `detail` is appended to the line.
  void Update(long done, long total, const std::string& detail = "");
  // For a job without an end (a served field): "label 12.3 s detail", drawn as Update
  // draws. Does not look for Ctrl-C: such a job stops on it by itself.
  void Status(const std::string& detail);
  // Clears the line.
  void Finish();

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace twinsim
