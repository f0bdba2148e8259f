#include "scene/run_log_stream.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/error.h"
#include "scene/command_log.h"
#include "scene/scene_run.h"

namespace twinsim {

RunLogStream::RunLogStream(std::string folder, std::vector<std::string> robot_names, bool ball, double frame_rate,
                           bool background)
    : folder_(std::move(folder)),
      robot_names_(std::move(robot_names)),
      ball_(ball),
      frame_rate_(frame_rate),
      background_(background) {
  // Started here, on the caller's thread before any frame: a thread started later from
  // serve's frame loop would inherit its real-time priority and CPU, and write a backlog
  // at the loop's priority, on its core.
  if (background_) writer_ = std::thread([this] { WriterLoop(); });
}

RunLogStream::~RunLogStream() {
  try {
    Finish();
  } catch (const std::exception&) {
    // Finish() reports it; a destructor cannot
  }
}

void RunLogStream::Finish() {
  if (!writer_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    QueueHeld();
    done_ = true;
  }
  wake_.notify_one();
  writer_.join();
  if (!error_.empty()) throw InputError(error_);
}

void RunLogStream::QueueHeld() {
  for (std::vector<std::string>& frame : held_) queue_.push_back(std::move(frame));
  held_.clear();
}

void RunLogStream::Write(const std::vector<std::string>& lines) {
  // The files are created by the first write (the headers), on the writer's thread when
  // there is one: creating a file, or emptying a large one left by an earlier match,
  // can take the file system a hundred milliseconds, and serve's frame loop must not wait.
  if (files_.empty()) {
    std::vector<AppendFile> files;  // all or none: a write after a failed one tries again
    for (const std::string& name : names_) files.emplace_back(folder_.empty() ? name : folder_ + "/" + name);
    files_ = std::move(files);
  }
  for (std::size_t f = 0; f < files_.size(); ++f)
    if (!lines[f].empty()) files_[f].Append(lines[f]);
}

void RunLogStream::WriterLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return done_ || !queue_.empty(); });
    if (queue_.empty()) return;  // done, and everything written
    std::vector<std::string> frame = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    room_.notify_one();
    std::string failed;
    try {
      Write(frame);
    } catch (const std::exception& e) {
      failed = e.what();
    }
    for (std::string& l : frame) l.clear();
    lock.lock();
    if (spare_.size() < kSpareFrames && frame.size() == names_.size()) spare_.push_back(std::move(frame));
    if (!failed.empty()) {
      error_ = failed;
      queue_.clear();
      room_.notify_all();
      return;
    }
  }
}

void RunLogStream::Open() {
  std::vector<std::pair<std::string, const char*>> files;  // name, header
  for (std::size_t i = 0; i < robot_names_.size(); ++i) {
    const std::string suffix = i == 0 ? "" : "_" + robot_names_[i];
    files.emplace_back("trajectory" + suffix + ".csv", kOmniLogHeader);
    files.emplace_back("truth" + suffix + ".csv", kTruthHeader);
  }
  if (ball_) files.emplace_back("ball.csv", kBallHeader);
  files.emplace_back("commands.csv", kCommandsHeader);
  // Created, headers first, by the first Write: here without a writer thread (a path
  // that cannot be created is named at once), else by the writer (named by the next
  // Append or by Finish).
  std::vector<std::string> headers;
  for (const auto& [name, header] : files) {
    headers.emplace_back(header);
    names_.push_back(name);
  }
  lines_.resize(names_.size());
  if (!background_) {
    try {
      Write(headers);
    } catch (...) {
      names_.clear();  // the next frame tries again, headers first
      lines_.clear();
      throw;
    }
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.push_back(std::move(headers));
}

void RunLogStream::Append(const std::vector<FrameRecord>& records, const BallRecord* ball) {
  if (records.size() != robot_names_.size())
    throw std::invalid_argument("RunLogStream::Append: records of another number of robots");
  if (names_.empty()) Open();
  for (std::string& l : lines_) l.clear();
  std::string& commands = lines_.back();
  for (std::size_t i = 0; i < records.size(); ++i) {
    AppendObserverRow(records[i], &lines_[2 * i]);
    AppendTruthRow(records[i], &lines_[2 * i + 1]);
    // The frame as CommandsCsv numbers it: from the record's own time.
    AppendCommandRow(std::llround(records[i].t * frame_rate_), robot_names_[i], records[i], &commands);
  }
  if (ball_ && ball != nullptr) AppendBallRow(*ball, &lines_[2 * records.size()]);
  ++frames_;
  if (!background_) {
    // In file order: commands.csv last, so that it never holds a frame the others lack.
    Write(lines_);
    return;
  }
  // The frame loop never waits on the writer: while the writer holds the queue (it may
  // have been preempted there by a busy machine, and a real-time frame loop would wait
  // for it: a priority inversion), the frame stays in held_ and goes with the next one.
  // Only a queue full to its cap (the disk far behind) makes it wait.
  held_.push_back(std::move(lines_));
  lines_.assign(names_.size(), std::string());
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() && held_.size() < kMaxQueuedFrames) return;
  if (!lock.owns_lock()) lock.lock();
  room_.wait(lock, [this] { return queue_.size() + held_.size() <= kMaxQueuedFrames || !error_.empty(); });
  if (!error_.empty()) throw InputError(error_);
  QueueHeld();
  if (!spare_.empty()) {
    lines_ = std::move(spare_.back());
    spare_.pop_back();
  }
  lock.unlock();
  wake_.notify_one();
}

std::vector<std::string> RunLogStream::names() const { return names_; }

}  // namespace twinsim
