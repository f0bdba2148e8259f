#include "robots/omni/omni_log.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"

namespace twinsim {
namespace {

// A gap between rows may be a whole number of frames give or take this fraction.
constexpr double kFrameJitter = 0.3;
// What a camera over a field can report. Beyond these a log is not a robot's (a unit
// mistake, a corrupted file), and replaying it would take hours or overflow the engines.
constexpr double kMinFramePeriod = 1e-4;  // s (10 kHz)
constexpr double kMaxFramePeriod = 1.0;   // s (1 Hz)
constexpr double kMaxFrames = 1e7;        // frames spanned by one log (3.8 days at 30 fps)
constexpr double kMaxPosition = 1e4;      // m from the field's origin
constexpr double kMaxAngle = 1e6;         // rad, unwrapped
constexpr double kMaxSpeedCommand = 100;  // m/s
constexpr double kMaxTurnCommand = 1000;  // rad/s

// Refuses a row whose numbers no robot on a field produces.
void CheckRowRange(const OmniLogRow& row, const SourceLocation& where) {
  auto refuse = [&](const char* what, double v, double most, const char* unit) {
    std::ostringstream msg;
    msg << what << " = " << v << " " << unit << " is beyond what a robot on a field reports (|" << what
        << "| <= " << most << ")";
    throw InputError(where, msg.str());
  };
  if (std::abs(row.pose.x) > kMaxPosition) refuse("x", row.pose.x, kMaxPosition, "m");
  if (std::abs(row.pose.y) > kMaxPosition) refuse("y", row.pose.y, kMaxPosition, "m");
  if (std::abs(row.pose.theta) > kMaxAngle) refuse("theta", row.pose.theta, kMaxAngle, "rad");
  if (std::abs(row.command.vx) > kMaxSpeedCommand) refuse("vx_cmd", row.command.vx, kMaxSpeedCommand, "m/s");
  if (std::abs(row.command.vy) > kMaxSpeedCommand) refuse("vy_cmd", row.command.vy, kMaxSpeedCommand, "m/s");
  if (std::abs(row.command.omega) > kMaxTurnCommand) refuse("omega_cmd", row.command.omega, kMaxTurnCommand, "rad/s");
}

}  // namespace

OmniLog OmniLogFromTable(const CsvTable& table) {
  // The first bad value in these columns is named; other columns are ignored.
  const std::vector<int> col = table.RequireColumns({"t", "x", "y", "theta", "vx_cmd", "vy_cmd", "omega_cmd"});

  OmniLog log;
  log.path = table.path;
  log.line_of = table.line_of;
  if (table.rows.size() < 2)
    throw InputError(SourceLocation{table.path, table.rows.empty() ? 1 : table.line_of[0]},
                     "a log needs at least 2 rows, got " + std::to_string(table.rows.size()));
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    const auto& r = table.rows[i];
    OmniLogRow row;
    row.t = r[col[0]];
    row.pose = Pose2{r[col[1]], r[col[2]], r[col[3]]};
    row.command = Twist2{r[col[4]], r[col[5]], r[col[6]]};
    CheckRowRange(row, SourceLocation{table.path, table.line_of[i]});
    log.rows.push_back(row);
  }

  std::vector<double> dts;
  for (std::size_t i = 1; i < log.rows.size(); ++i) {
    const double dt = log.rows[i].t - log.rows[i - 1].t;
    if (dt <= 0) {
      std::ostringstream msg;
      msg << "time goes backwards or stands still: t = " << log.rows[i].t << " after " << log.rows[i - 1].t;
      throw InputError(SourceLocation{table.path, table.line_of[i], 1}, msg.str());
    }
    dts.push_back(dt);
  }
  std::vector<double> sorted = dts;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  log.frame_period = sorted[sorted.size() / 2];
  if (!(log.frame_period >= kMinFramePeriod && log.frame_period <= kMaxFramePeriod)) {
    std::ostringstream msg;
    msg << "the frame period (the median time between rows) is " << log.frame_period << " s; a camera log has "
        << kMinFramePeriod << " to " << kMaxFramePeriod << " s between frames (is 't' in seconds?)";
    throw InputError(SourceLocation{table.path, table.line_of[0], 1}, msg.str());
  }
  const double span = (log.rows.back().t - log.rows.front().t) / log.frame_period;
  if (span > kMaxFrames) {
    std::ostringstream msg;
    msg << "the log spans " << span << " frames of " << log.frame_period << " s; at most " << kMaxFrames
        << " are replayed (split the log)";
    throw InputError(SourceLocation{table.path, table.line_of.back(), 1}, msg.str());
  }
  for (std::size_t i = 0; i < dts.size(); ++i) {
    const double frames = dts[i] / log.frame_period;
    if (std::abs(frames - std::round(frames)) > kFrameJitter) {
      std::ostringstream msg;
      msg << "irregular frame time: " << dts[i] << " s after the previous row, the frame period is "
          << log.frame_period << " s";
      throw InputError(SourceLocation{table.path, table.line_of[i + 1], 1}, msg.str());
    }
  }

  // Unwrap theta: successive frames never turn by more than half a turn.
  for (std::size_t i = 1; i < log.rows.size(); ++i) {
    const double prev = log.rows[i - 1].pose.theta;
    log.rows[i].pose.theta = prev + WrapAngle(log.rows[i].pose.theta - prev);
  }
  return log;
}

int OmniLog::FrameIndex(std::size_t row) const {
  return static_cast<int>(std::lround((rows[row].t - rows[0].t) / frame_period));
}

OmniLog ReadOmniLog(const std::string& path) { return OmniLogFromTable(ReadCsvTable(path)); }
OmniLog ParseOmniLog(const std::string& text, const std::string& path) {
  return OmniLogFromTable(ParseCsvTable(text, path));
}

std::string FormatOmniLog(const std::vector<OmniLogRow>& rows) {
  std::string out = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n";
  for (const auto& r : rows) {
    const double v[] = {r.t, r.pose.x, r.pose.y, r.pose.theta, r.command.vx, r.command.vy, r.command.omega};
    for (int i = 0; i < 7; ++i) {
      if (i) out += ',';
      out += FormatCsvNumber(v[i]);
    }
    out += '\n';
  }
  return out;
}

void WriteOmniLog(const std::string& path, const std::vector<OmniLogRow>& rows) {
  WriteFileAtomically(path, FormatOmniLog(rows));
}

void WritePoseCsv(const std::string& path, const std::vector<double>& t, const std::vector<Pose2>& poses) {
  std::string out = "t,x,y,theta\n";
  for (std::size_t i = 0; i < t.size(); ++i) {
    out += FormatCsvNumber(t[i]) + ',' + FormatCsvNumber(poses[i].x) + ',' + FormatCsvNumber(poses[i].y) + ',' +
           FormatCsvNumber(poses[i].theta) + '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace twinsim
