#include "robots/omni/omni_log.h"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"

namespace twinsim {
namespace {

// Rows closer than this share of the frame period are not two camera frames. Any gap
// longer is a whole number of frames, rounded: a real logger's clock jitters by up to
// a third of a frame (the Robotino's: 0.7 to 1.66 periods between rows), and a gap that
// rounds to two frames or more is a hole, frames the logger never wrote.
constexpr double kMinFrameStep = 0.5;
// The longest hole the observer carries the state across (the commands held): longer,
// nothing of the robot's velocity is left, and the log is two logs.
constexpr double kMaxHoleSeconds = 5.0;
// What a camera over a field can report. Beyond these a log is not a robot's (a unit
// mistake, a corrupted file), and replaying it would take hours or overflow the engines.
constexpr double kMinFramePeriod = 1e-4;  // s (10 kHz)
constexpr double kMaxFramePeriod = 1.0;   // s (1 Hz)
constexpr double kMaxFrames = 1e7;        // frames spanned by one log (3.8 days at 30 fps)
constexpr double kMaxPosition = 1e4;      // m from the field's origin
constexpr double kMaxAngle = 1e6;         // rad, unwrapped

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

namespace {

// Numbers compare as numbers ("3" is "3.0"), anything else as text, case-insensitively.
bool SameLabel(const std::string& a, const std::string& b) {
  char* end_a = nullptr;
  char* end_b = nullptr;
  const double x = std::strtod(a.c_str(), &end_a);
  const double y = std::strtod(b.c_str(), &end_b);
  if (!a.empty() && !b.empty() && *end_a == '\0' && *end_b == '\0') return x == y;
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char p, char q) {
           return std::tolower(static_cast<unsigned char>(p)) == std::tolower(static_cast<unsigned char>(q));
         });
}

// The rows of `table` that belong to the robot `select` names (all rows when the file
// holds one robot). Throws InputError when that is ambiguous or matches nothing.
std::vector<std::size_t> SelectRows(const CsvTable& table, const OmniLogSelector& select, std::string* robot) {
  int id_column = -1;
  for (const char* name : {"robot_id", "robot", "id"}) {
    if (id_column < 0) id_column = table.Column(name);
  }
  const int team_column = table.Column("team");
  std::vector<std::size_t> all(table.rows.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  if (id_column < 0 && team_column < 0) {
    if (!select.empty()) {
      throw InputError(SourceLocation{table.path, 1},
                       "the log has no robot_id, robot, id or team column to select a robot by");
    }
    return all;
  }
  auto label = [&](int column, std::size_t row) -> std::string {
    if (column < 0) return "";
    const auto& text = table.label[static_cast<std::size_t>(column)];
    if (row < text.size()) return text[row];
    const double v = table.rows[row][static_cast<std::size_t>(column)];  // a table held in memory
    return std::isfinite(v) ? FormatCsvNumber(v) : std::string();
  };
  auto name_of = [&](std::size_t row) {
    const std::string team = label(team_column, row), id = label(id_column, row);
    return team.empty() ? id : id.empty() ? team : team + " " + id;
  };
  std::vector<std::string> robots;  // distinct, in order of first appearance
  std::vector<std::size_t> kept;
  for (std::size_t i : all) {
    const std::string name = name_of(i);
    if (std::find(robots.begin(), robots.end(), name) == robots.end()) robots.push_back(name);
    const bool match = (select.robot.empty() || SameLabel(label(id_column, i), select.robot)) &&
                       (select.team.empty() || SameLabel(label(team_column, i), select.team));
    if (match) kept.push_back(i);
  }
  std::string list;
  for (const auto& r : robots) list += (list.empty() ? "" : ", ") + (r.empty() ? std::string("(blank)") : r);
  if (kept.empty()) {
    const std::string wanted = select.team.empty() ? select.robot
                               : select.robot.empty() ? select.team
                                                      : select.team + " " + select.robot;
    throw InputError(SourceLocation{table.path, 1}, "no rows for robot '" + wanted + "' (the log holds: " + list + ")");
  }
  std::vector<std::string> chosen;
  for (std::size_t i : kept) {
    const std::string name = name_of(i);
    if (std::find(chosen.begin(), chosen.end(), name) == chosen.end()) chosen.push_back(name);
  }
  if (chosen.size() > 1) {
    throw InputError(SourceLocation{table.path, table.line_of[kept.front()]},
                     "the log holds " + std::to_string(robots.size()) + " robots (" + list +
                         "): choose one with --robot ID (and --team TEAM where ids repeat)");
  }
  *robot = chosen.front();
  return kept;
}

// Gives frames with empty pose cells a pose interpolated in time between the measured
// frames around them (theta already unwrapped). A repeated pose keeps the value the
// camera sent: nothing is invented where the file holds a number.
void FillUnmeasured(OmniLog* log, const std::vector<char>& empty) {
  std::vector<OmniLogRow>& rows = log->rows;
  std::size_t previous = rows.size();  // the last measured row so far
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].measured) continue;
    if (previous < rows.size()) {
      const OmniLogRow& a = rows[previous];
      for (std::size_t k = previous + 1; k < i; ++k) {
        if (!empty[k]) continue;
        const double u = (rows[k].t - a.t) / (rows[i].t - a.t);
        rows[k].pose = Pose2{a.pose.x + u * (rows[i].pose.x - a.pose.x), a.pose.y + u * (rows[i].pose.y - a.pose.y),
                             a.pose.theta + u * (rows[i].pose.theta - a.pose.theta)};
      }
    } else {
      for (std::size_t k = 0; k < i; ++k) rows[k].pose = rows[i].pose;  // only empty rows come before
    }
    previous = i;
  }
  for (std::size_t k = previous + 1; k < rows.size(); ++k)
    if (empty[k]) rows[k].pose = rows[previous].pose;
}

// Puts each pose's theta on one continuous branch. From one frame to the next a robot
// turns by less than half a turn, so the nearest branch is the right one. Across frames
// without a pose (lost, or a hole in the clock) it may have turned further: the branch
// is then the one nearest the turn extrapolated at the rate measured just before the gap
// (over up to kRateFrames frames of consecutive measurements), so a robot spinning at
// 6 rad/s keeps its count of turns across a stall of the logger.
void UnwrapHeadings(OmniLog* log_out, const std::vector<char>& empty) {
  constexpr std::size_t kRateFrames = 4;
  constexpr double kGapFrames = 1.5;  // a gap longer than this many frame periods is extrapolated over
  OmniLog& log = *log_out;
  std::vector<const OmniLogRow*> run;  // the measured rows of the current gapless stretch, newest last
  const OmniLogRow* prev = nullptr;    // the last row with a pose, measured or repeated
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    OmniLogRow& row = log.rows[i];
    if (empty[i]) continue;
    if (!prev) {
      prev = &row;
      if (row.measured) run.push_back(&row);
      continue;
    }
    row.pose.theta = prev->pose.theta + WrapAngle(row.pose.theta - prev->pose.theta);  // the nearest branch
    const OmniLogRow& last = *run.back();
    const double gap = row.t - last.t;
    // Across a gap, the branch nearest the turn extrapolated from the last measurement (a
    // repeated pose is the last one sent again: it never turns).
    if (row.measured && gap > kGapFrames * log.frame_period && run.size() >= 2) {
      const double expected = last.pose.theta + (last.pose.theta - run.front()->pose.theta) / (last.t - run.front()->t) * gap;
      row.pose.theta += 2 * kPi * std::round((expected - row.pose.theta) / (2 * kPi));
    }
    prev = &row;
    if (!row.measured) continue;
    if (gap > kGapFrames * log.frame_period) run.clear();
    run.push_back(&row);
    if (run.size() > kRateFrames + 1) run.erase(run.begin());
  }
}

// Each row's frame counted from the one before (a real clock jitters: counted from the
// first row, jitter that does not average out would put two rows on one frame), and the
// holes in the clock. `dts` are the gaps between rows. Throws InputError for two rows
// under half a period apart and for a hole too long to bridge.
void CountFrames(const std::vector<double>& dts, const std::string& path, OmniLog* log_out) {
  OmniLog& log = *log_out;
  log.frame_of.assign(log.rows.size(), 0);
  for (std::size_t i = 0; i < dts.size(); ++i) {
    const double frames = dts[i] / log.frame_period;
    if (frames < kMinFrameStep) {
      std::ostringstream msg;
      msg << "irregular frame time: " << dts[i] << " s after the previous row, under half the frame period "
          << log.frame_period << " s (two rows for one camera frame?)";
      throw InputError(SourceLocation{path, log.line_of[i + 1], 1}, msg.str());
    }
    const int step = std::max(1, static_cast<int>(std::lround(frames)));
    log.frame_of[i + 1] = log.frame_of[i] + step;
    if (step < 2) continue;
    if (dts[i] > kMaxHoleSeconds) {
      std::ostringstream msg;
      msg << "a hole of " << dts[i] << " s in the clock (no row for " << step - 1 << " frames); holes up to "
          << kMaxHoleSeconds << " s read as frames without a measurement, a longer one is two logs: split it here";
      throw InputError(SourceLocation{path, log.line_of[i + 1], 1}, msg.str());
    }
    log.holes.push_back({i + 1, dts[i], step - 1});
  }
}

}  // namespace

OmniLog OmniLogFromTable(const CsvTable& table, const OmniLogSelector& select) {
  // The first bad value in these columns is named; other columns are ignored. Pose cells
  // may be empty (a frame without a measurement).
  const std::vector<int> col =
      table.RequireColumns({"t", "x", "y", "theta", "vx_cmd", "vy_cmd", "omega_cmd"}, {"x", "y", "theta"});

  OmniLog log;
  log.path = table.path;
  if (table.rows.size() < 2)
    throw InputError(SourceLocation{table.path, table.rows.empty() ? 1 : table.line_of[0]},
                     "a log needs at least 2 rows, got " + std::to_string(table.rows.size()));
  const std::vector<std::size_t> selected = SelectRows(table, select, &log.robot);
  bool have_measured = false;
  Pose2 last_raw;
  std::vector<char> empty;  // per row: its pose cells are empty
  for (std::size_t i : selected) {
    const auto& r = table.rows[i];
    OmniLogRow row;
    row.t = r[col[0]];
    row.pose = Pose2{r[col[1]], r[col[2]], r[col[3]]};
    row.command = Twist2{r[col[4]], r[col[5]], r[col[6]]};
    const int empty_cells = std::isnan(row.pose.x) + std::isnan(row.pose.y) + std::isnan(row.pose.theta);
    if (empty_cells == 3) {
      row.measured = false;
    } else if (empty_cells > 0) {
      const int c = std::isnan(row.pose.x) ? col[1] : std::isnan(row.pose.y) ? col[2] : col[3];
      throw InputError(SourceLocation{table.path, table.line_of[i]},
                       "column '" + table.header[static_cast<std::size_t>(c)] +
                           "' is empty but the row's other pose cells are not: x, y and theta are all empty (a "
                           "frame without a measurement) or all numbers");
    } else if (have_measured && row.pose.x == last_raw.x && row.pose.y == last_raw.y &&
               row.pose.theta == last_raw.theta) {
      row.measured = false;  // the camera repeated its last pose
    }
    CheckRowRange(row, SourceLocation{table.path, table.line_of[i]});
    empty.push_back(empty_cells == 3);
    log.rows.push_back(row);
    log.line_of.push_back(table.line_of[i]);
    if (row.measured) {
      last_raw = row.pose;
      have_measured = true;
    }
  }
  if (log.rows.size() < 2)
    throw InputError(SourceLocation{table.path, log.line_of.front()},
                     "a log needs at least 2 rows, got " + std::to_string(log.rows.size()));
  if (log.num_measured() == 0) {
    throw InputError(SourceLocation{table.path, log.line_of.front()},
                     "no row holds a pose (x, y and theta are empty on every row" +
                         (log.robot.empty() ? std::string(")") : " of robot " + log.robot + ")"));
  }

  std::vector<double> dts;
  for (std::size_t i = 1; i < log.rows.size(); ++i) {
    const double dt = log.rows[i].t - log.rows[i - 1].t;
    if (dt <= 0) {
      std::ostringstream msg;
      msg << "time goes backwards or stands still: t = " << log.rows[i].t << " after " << log.rows[i - 1].t;
      throw InputError(SourceLocation{table.path, log.line_of[i], 1}, msg.str());
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
    throw InputError(SourceLocation{table.path, log.line_of[0], 1}, msg.str());
  }
  // The frames a replay runs through, bounded before (by the clock) and after (as
  // counted gap by gap, each gap at least one frame) counting them.
  auto refuse_beyond_max_frames = [&](auto frames) {  // printed as given: the clock's span, or a count
    if (frames <= kMaxFrames) return;
    std::ostringstream msg;
    msg << "the log spans " << frames << " frames of " << log.frame_period << " s; at most " << kMaxFrames
        << " are replayed (split the log)";
    throw InputError(SourceLocation{table.path, log.line_of.back(), 1}, msg.str());
  };
  refuse_beyond_max_frames((log.rows.back().t - log.rows.front().t) / log.frame_period);
  CountFrames(dts, table.path, &log);
  refuse_beyond_max_frames(log.frame_of.back());

  UnwrapHeadings(&log, empty);
  FillUnmeasured(&log, empty);
  return log;
}

std::string DescribeClockHoles(const OmniLog& log) {
  if (log.holes.empty()) return "";
  const ClockHole* longest = &log.holes.front();
  int frames = 0;
  for (const ClockHole& h : log.holes) {
    frames += h.frames;
    if (h.seconds > longest->seconds) longest = &h;
  }
  char text[320];
  std::snprintf(text, sizeof text,
                ": the clock has %zu hole(s) where the logger wrote no row (%d frame(s) in all, the longest %.3g s "
                "before line %d): read as frames without a measurement, the command held",
                log.holes.size(), frames, longest->seconds, log.line_of[longest->row]);
  return log.path + text;  // the path apart: it may be longer than any buffer
}

int OmniLog::num_measured() const {
  int n = 0;
  for (const OmniLogRow& r : rows) n += r.measured;
  return n;
}

int OmniLog::FrameIndex(std::size_t row) const {
  if (frame_of.size() == rows.size()) return frame_of[row];
  return static_cast<int>(std::lround((rows[row].t - rows[0].t) / frame_period));
}

std::vector<Twist2> OmniLog::CommandAtEveryFrame() const {
  if (rows.empty()) return {};
  std::vector<Twist2> out(static_cast<std::size_t>(FrameIndex(rows.size() - 1)) + 1);
  for (std::size_t f = 0, row = 0; f < out.size(); ++f) {
    while (row + 1 < rows.size() && FrameIndex(row + 1) <= static_cast<int>(f)) ++row;
    out[f] = rows[row].command;
  }
  return out;
}

OmniLog ReadOmniLog(const std::string& path, const OmniLogSelector& select) {
  return OmniLogFromTable(ReadCsvTable(path), select);
}
OmniLog ParseOmniLog(const std::string& text, const std::string& path, const OmniLogSelector& select) {
  return OmniLogFromTable(ParseCsvTable(text, path), select);
}

void AppendOmniLogRow(const OmniLogRow& r, std::string* out) {
  const double v[] = {r.t, r.pose.x, r.pose.y, r.pose.theta, r.command.vx, r.command.vy, r.command.omega};
  for (int i = 0; i < 7; ++i) {
    if (i) *out += ',';
    if (r.measured || i == 0 || i > 3) *out += FormatCsvNumber(v[i]);  // no measurement: empty pose cells
  }
  *out += '\n';
}

std::string FormatOmniLog(const std::vector<OmniLogRow>& rows) {
  std::string out = kOmniLogHeader;
  for (const auto& r : rows) AppendOmniLogRow(r, &out);
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

std::string FormatPoseSamplesCsv(const std::vector<double>& t, const std::vector<std::vector<Pose2>>& samples) {
  std::string out = "t,sample,x,y,theta\n";
  for (std::size_t i = 0; i < t.size(); ++i) {
    for (std::size_t k = 0; k < samples[i].size(); ++k) {
      const Pose2& p = samples[i][k];
      if (!IsFinite(p)) continue;
      out += FormatCsvNumber(t[i]) + ',' + std::to_string(k) + ',' + FormatCsvNumber(p.x) + ',' + FormatCsvNumber(p.y) +
             ',' + FormatCsvNumber(p.theta) + '\n';
    }
  }
  return out;
}

void WritePoseSamplesCsv(const std::string& path, const std::vector<double>& t,
                         const std::vector<std::vector<Pose2>>& samples) {
  WriteFileAtomically(path, FormatPoseSamplesCsv(t, samples));
}

OmniTypicalMotion TypicalMotionOf(const std::vector<const OmniLog*>& logs) {
  double speed = 0, turn = 0;
  long count = 0;
  for (const OmniLog* log : logs) {
    for (std::size_t i = 1; i < log->rows.size(); ++i) {
      const OmniLogRow &a = log->rows[i - 1], &b = log->rows[i];
      if (!a.measured || !b.measured || b.t <= a.t) continue;
      speed += std::hypot(b.pose.x - a.pose.x, b.pose.y - a.pose.y) / (b.t - a.t);
      turn += std::abs(WrapAngle(b.pose.theta - a.pose.theta)) / (b.t - a.t);
      ++count;
    }
  }
  if (count == 0) return {};
  return {std::min(speed / static_cast<double>(count), 3.0), std::min(turn / static_cast<double>(count), 20.0)};
}

OmniLog SliceOmniLog(const OmniLog& log, std::size_t first, std::size_t last) {
  OmniLog out;
  out.path = log.path;
  out.robot = log.robot;
  out.frame_period = log.frame_period;
  out.rows.assign(log.rows.begin() + static_cast<long>(first), log.rows.begin() + static_cast<long>(last));
  out.line_of.assign(log.line_of.begin() + static_cast<long>(first), log.line_of.begin() + static_cast<long>(last));
  if (log.frame_of.size() == log.rows.size()) {
    for (std::size_t i = first; i < last; ++i) out.frame_of.push_back(log.frame_of[i] - log.frame_of[first]);
  }
  for (ClockHole h : log.holes) {
    if (h.row <= first || h.row >= last) continue;  // a hole before the slice's first row is not in it
    h.row -= first;
    out.holes.push_back(h);
  }
  return out;
}

}  // namespace twinsim
