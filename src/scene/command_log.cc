#include "scene/command_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <tuple>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/csv_table.h"
#include "sim/command_limits.h"

namespace twinsim {
namespace {

// 17 significant digits: every double reads back as itself.
std::string Exact(double v) {
  if (v == 0) return "0";  // no "-0"
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The limits `twinsim serve` takes from the network (sim/command_limits.h), so that a
// file holds what a team could have sent.
constexpr double kMaxKickRadians = kMaxKickAngle * kPi / 180;
constexpr double kMaxLogFrames = 1e7;

}  // namespace

void AppendCommandRow(long long frame, const std::string& robot, const FrameRecord& f, std::string* out) {
  if (!f.present) return;  // off the field: sent nothing
  *out += std::to_string(frame) + ',' + FormatCsvNumber(f.t) + ',' + robot;
  for (double v : {f.command.vx, f.command.vy, f.command.omega, f.ball_command.kick_speed, f.ball_command.kick_angle,
                   f.ball_command.dribbler_speed})
    *out += ',' + Exact(v);
  *out += '\n';
}

std::string CommandsCsv(const SimulationResult& result) {
  std::string out = kCommandsHeader;
  // Frame by frame, the robots in the field's order; a robot off the field sends
  // nothing and has no row (rows go by each record's own frame).
  std::vector<std::tuple<long long, std::size_t, const FrameRecord*>> rows;
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    for (const FrameRecord& f : result.frames[i])
      if (f.present) rows.emplace_back(std::llround(f.t * result.timing.frame_rate), i, &f);
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
  });
  for (const auto& [frame, i, f] : rows) AppendCommandRow(frame, result.robot_names[i], *f, &out);
  return out;
}

CommandLog ReadCommandLog(const std::string& path, const std::string& robot, double frame_rate) {
  const CsvTable table = ReadCsvTable(path);
  const int vx = table.RequireColumn("vx_cmd"), vy = table.RequireColumn("vy_cmd"),
            omega = table.RequireColumn("omega_cmd");
  const bool by_frame = table.Column("frame") >= 0;
  const int time = table.RequireColumn(by_frame ? "frame" : "t");
  const int robots = table.Column("robot");
  auto optional_column = [&](const char* name) { return table.Column(name) >= 0 ? table.RequireColumn(name) : -1; };
  const int kick = optional_column("kick_speed"), angle = optional_column("kick_angle"),
            dribbler = optional_column("dribbler_speed");

  CommandLog log;
  log.path = path;
  std::set<std::string> names;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (robots >= 0) {
      const std::string& name = table.label[static_cast<std::size_t>(robots)][r];
      names.insert(name);
      if (name != robot) continue;
    }
    const std::vector<double>& row = table.rows[r];
    const SourceLocation at{path, table.line_of[r]};
    auto value = [&](int column, double low, double high, const char* unit) {
      const double v = row[static_cast<std::size_t>(column)];
      if (v < low || v > high) {
        char range[96];
        std::snprintf(range, sizeof range, " is %g, outside %g..%g %s", v, low, high, unit);
        throw InputError(SourceLocation{path, table.line_of[r], column + 1},
                         "'" + table.header[static_cast<std::size_t>(column)] + "'" + range);
      }
      return v;
    };
    const double when = row[static_cast<std::size_t>(time)];
    const double frame = by_frame ? when : std::round(when * frame_rate);
    if (by_frame && frame != std::round(frame)) throw InputError(at, "frame " + Exact(when) + " is not a whole number");
    // A run keeps every frame (scene.h: at most 1e7), so a replay ends before that.
    if (frame < 0 || frame >= kMaxLogFrames)
      throw InputError(at, "frame " + Exact(frame) + " is outside 0.." + Exact(kMaxLogFrames - 1) +
                               " (a run keeps at most 1e7 frames)");
    if (!log.frames.empty() && frame <= log.frames.back()) {
      throw InputError(at, "frame " + std::to_string(static_cast<long long>(frame)) + " does not come after frame " +
                               std::to_string(log.frames.back()) + (robots >= 0 ? " of robot '" + robot + "'" : "") +
                               ": rows must be in time order, one per frame");
    }
    log.frames.push_back(static_cast<int>(frame));
    log.moves.push_back(Twist2{value(vx, -kMaxCommandSpeed, kMaxCommandSpeed, "m/s"),
                               value(vy, -kMaxCommandSpeed, kMaxCommandSpeed, "m/s"),
                               value(omega, -kMaxCommandOmega, kMaxCommandOmega, "rad/s")});
    BallCommand ball;
    if (kick >= 0) ball.kick_speed = value(kick, 0, kMaxKickSpeed, "m/s");
    if (angle >= 0) ball.kick_angle = value(angle, 0, kMaxKickRadians, "rad");
    if (dribbler >= 0) ball.dribbler_speed = value(dribbler, 0, kMaxDribblerSpeed, "rpm");
    log.balls.push_back(ball);
  }
  if (log.frames.empty()) {
    if (robots < 0) throw InputError(SourceLocation{path, 1}, "no commands: the file has no rows");
    std::string have;
    for (const std::string& n : names) have += (have.empty() ? "" : ", ") + n;
    throw InputError(SourceLocation{path, 1},
                     "no rows for robot '" + robot + "' (robots in the file: " + (have.empty() ? "none" : have) + ")");
  }
  return log;
}

LogCommandSource::LogCommandSource(std::shared_ptr<const CommandLog> log) : log_(std::move(log)) {}

int LogCommandSource::RowAt(int frame) const {
  const auto it = std::upper_bound(log_->frames.begin(), log_->frames.end(), frame);
  return static_cast<int>(it - log_->frames.begin()) - 1;
}

Twist2 LogCommandSource::Command(const BehaviourInput& in) {
  const int row = RowAt(in.frame);
  return row < 0 ? Twist2{} : log_->moves[static_cast<std::size_t>(row)];
}

BallCommand LogCommandSource::Ball(const BehaviourInput& in) {
  const int row = RowAt(in.frame);
  if (row < 0) return BallCommand{};
  BallCommand b = log_->balls[static_cast<std::size_t>(row)];
  if (log_->frames[static_cast<std::size_t>(row)] != in.frame) b.kick_speed = b.kick_angle = 0;
  return b;
}

}  // namespace twinsim
