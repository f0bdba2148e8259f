#include "scene/run_log_stream.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "scene/command_log.h"
#include "scene/scene_run.h"

namespace twinsim {

RunLogStream::RunLogStream(std::string folder, std::vector<std::string> robot_names, bool ball, double frame_rate)
    : folder_(std::move(folder)), robot_names_(std::move(robot_names)), ball_(ball), frame_rate_(frame_rate) {}

void RunLogStream::Open() {
  std::vector<std::pair<std::string, const char*>> files;  // name, header
  for (std::size_t i = 0; i < robot_names_.size(); ++i) {
    const std::string suffix = i == 0 ? "" : "_" + robot_names_[i];
    files.emplace_back("trajectory" + suffix + ".csv", kOmniLogHeader);
    files.emplace_back("truth" + suffix + ".csv", kTruthHeader);
  }
  if (ball_) files.emplace_back("ball.csv", kBallHeader);
  files.emplace_back("commands.csv", kCommandsHeader);
  for (const auto& [name, header] : files) {
    files_.emplace_back(folder_.empty() ? name : folder_ + "/" + name);
    files_.back().Append(header);
    names_.push_back(name);
  }
  lines_.resize(files_.size());
}

void RunLogStream::Append(const std::vector<FrameRecord>& records, const BallRecord* ball) {
  if (records.size() != robot_names_.size())
    throw std::invalid_argument("RunLogStream::Append: records of another number of robots");
  if (files_.empty()) Open();
  for (std::string& l : lines_) l.clear();
  std::string& commands = lines_.back();
  for (std::size_t i = 0; i < records.size(); ++i) {
    AppendObserverRow(records[i], &lines_[2 * i]);
    AppendTruthRow(records[i], &lines_[2 * i + 1]);
    // The frame as CommandsCsv numbers it: from the record's own time.
    AppendCommandRow(std::llround(records[i].t * frame_rate_), robot_names_[i], records[i], &commands);
  }
  if (ball_ && ball != nullptr) AppendBallRow(*ball, &lines_[2 * records.size()]);
  // In file order: commands.csv last, so that it never holds a frame the others lack.
  for (std::size_t f = 0; f < files_.size(); ++f)
    if (!lines_[f].empty()) files_[f].Append(lines_[f]);
  ++frames_;
}

std::vector<std::string> RunLogStream::names() const { return names_; }

}  // namespace twinsim
