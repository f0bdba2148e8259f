// The omni robot log of CONTRACT.md: `t,x,y,theta,vx_cmd,vy_cmd,omega_cmd`, one row per
// camera frame, SI units, extra columns ignored. One module reads and writes it.
//
// Reading checks every value (file:line:column), that t strictly increases by at least
// half a frame period between rows (each gap is read as a whole number of frames; one
// that rounds to two or more is a hole in the clock, frames without a measurement, up
// to 5 s), and unwraps theta. A row whose x, y, theta cells are
// all empty, or whose pose repeats the last measured pose exactly, is a frame with a
// command and no new measurement (OmniLogRow::measured false): cameras miss frames.
// A file holding several robots (a `robot_id`, `robot` or `id` column, and optionally
// `team`) is read for the one robot an OmniLogSelector names. Writing is atomic and
// byte-for-byte deterministic.
#pragma once

#include <string>
#include <vector>

#include "core/pose.h"

namespace twinsim {

struct CsvTable;

struct OmniLogRow {
  double t = 0;     // s
  Pose2 pose;       // field frame, theta unwrapped on reading
  Twist2 command;   // robot frame, sent at t
  // False for a frame without a new measurement; no fit or score may use its pose as a
  // measurement. Its pose is the camera's repeated one, or for empty cells interpolated
  // in time between the measured frames around it (held before the first and after the
  // last), for code that needs a pose.
  bool measured = true;
};

// Which robot of a log holding several to read ("" = any). Ids compare as numbers when
// both are numbers ("3" is "3.0"), else as text; teams as text, case-insensitively.
struct OmniLogSelector {
  std::string robot;  // a value of the robot id column
  std::string team;   // a value of the `team` column
  bool empty() const { return robot.empty() && team.empty(); }
};

// Frames the logger never wrote: a gap of two or more frame periods between rows (any
// fraction of a frame: a stalled logger resumes off the beat). Its frames read as frames
// without a measurement, the last row's command held.
struct ClockHole {
  std::size_t row = 0;  // the row after the hole
  double seconds = 0;   // from the row before to `row`
  int frames = 0;       // frames missing, rounded
};

struct OmniLog {
  std::string path;
  std::vector<OmniLogRow> rows;
  std::vector<int> line_of;  // file line of each row
  double frame_period = 0;   // s, the median time between rows
  std::string robot;         // which robot of the file, as selected ("" = the file's only one)
  std::vector<ClockHole> holes;  // in row order
  // Each row's frame from row 0, counted gap by gap as the reader found them (each gap
  // rounded to whole frames, at least one); empty for a log built in code, whose frames
  // FrameIndex counts from the time.
  std::vector<int> frame_of;

  // The frame index of row i counted from row 0 (dropped frames and holes leave gaps).
  int FrameIndex(std::size_t row) const;
  // The command in force at every frame from row 0's to the last row's, indexed by
  // FrameIndex: a frame without a row holds the row's before it.
  std::vector<Twist2> CommandAtEveryFrame() const;
  // Rows with a new measurement.
  int num_measured() const;
};

// Reads and checks a log; throws InputError "path:line:column: what is wrong", also
// when the file holds several robots and `select` does not name one of them, or names
// one it does not hold. OmniLogFromTable checks a table held in memory (TableFromRows)
// the same way.
OmniLog OmniLogFromTable(const CsvTable& table, const OmniLogSelector& select = {});
OmniLog ReadOmniLog(const std::string& path, const OmniLogSelector& select = {});
OmniLog ParseOmniLog(const std::string& text, const std::string& path, const OmniLogSelector& select = {});

// Logs whose frame periods (each its median step) differ by less than this share of the
// first's are one camera's, to be fitted together: a real logger's median step moves
// from run to run (the Robotino's: 31.0 to 31.8 ms, 2.4 %); each log is replayed at
// its own period.
inline constexpr double kSameCameraRate = 0.05;

// One sentence for the user on the log's clock holes ("" when it has none): how many,
// how many frames in all, the longest and where. Commands say it once per log.
std::string DescribeClockHoles(const OmniLog& log);

// The logs' typical motion: the mean translational speed (m/s, at most 3) and turn rate
// (rad/s either way, at most 20) between consecutive measured rows. The driving noise's
// fits (identify's, the learned backend's) search its spreads there rather than
// standing still, so that a growth with speed or turn rate tilts them about the logs'
// motion instead of raising them at every speed: with the spreads standing still as
// coordinates, a spread and its growth form a ridge a search moving one coordinate at a
// time stops on.
struct OmniTypicalMotion {
  double speed = 0, turn_rate = 0;
};
OmniTypicalMotion TypicalMotionOf(const std::vector<const OmniLog*>& logs);

// Rows [first, last) of `log` as a log of their own (path, robot and frame period kept).
OmniLog SliceOmniLog(const OmniLog& log, std::size_t first, std::size_t last);

// The largest commands a log may hold (|vx_cmd|, |vy_cmd|; |omega_cmd|): beyond them a
// row is refused as no robot on a field's, and a scene may not ask for more.
inline constexpr double kMaxSpeedCommand = 100;  // m/s
inline constexpr double kMaxTurnCommand = 1000;  // rad/s

// The CSV text of a log (header and rows).
std::string FormatOmniLog(const std::vector<OmniLogRow>& rows);
// The log's header line, and one row's line (a row without a measurement has empty
// pose cells), appended to *out: FormatOmniLog line by line, for a log written as it
// runs.
inline constexpr const char* kOmniLogHeader = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n";
void AppendOmniLogRow(const OmniLogRow& row, std::string* out);
// Writes a log atomically.
void WriteOmniLog(const std::string& path, const std::vector<OmniLogRow>& rows);

// Writes `t,x,y,theta` rows (a replay's output) atomically.
void WritePoseCsv(const std::string& path, const std::vector<double>& t, const std::vector<Pose2>& poses);
// t,sample,x,y,theta: samples[i] holds row i's draws (each row the same number), sample
// 0..N-1 in order (CONTRACT.md, replay --samples; run --samples); a pose that is not
// finite (a robot off the field) is left out. Written atomically by the second.
std::string FormatPoseSamplesCsv(const std::vector<double>& t, const std::vector<std::vector<Pose2>>& samples);
void WritePoseSamplesCsv(const std::string& path, const std::vector<double>& t,
                         const std::vector<std::vector<Pose2>>& samples);

}  // namespace twinsim
