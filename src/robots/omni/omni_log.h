// The omni robot log of CONTRACT.md: `t,x,y,theta,vx_cmd,vy_cmd,omega_cmd`, one row per
// camera frame, SI units, extra columns ignored. One module reads and writes it.
//
// Reading checks every value (file:line:column), that t strictly increases and is
// nearly uniform (gaps of whole frames, i.e. dropped frames, are fine), and unwraps
// theta. Writing is atomic and byte-for-byte deterministic.
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
};

struct OmniLog {
  std::string path;
  std::vector<OmniLogRow> rows;
  std::vector<int> line_of;  // file line of each row
  double frame_period = 0;   // s, the median time between rows

  // The frame index of row i counted from row 0 (dropped frames leave gaps).
  int FrameIndex(std::size_t row) const;
};

// Reads and checks a log; throws InputError "path:line:column: what is wrong".
// OmniLogFromTable checks a table held in memory (TableFromRows) the same way.
OmniLog OmniLogFromTable(const CsvTable& table);
OmniLog ReadOmniLog(const std::string& path);
OmniLog ParseOmniLog(const std::string& text, const std::string& path);

// The CSV text of a log (header and rows).
std::string FormatOmniLog(const std::vector<OmniLogRow>& rows);
// Writes a log atomically.
void WriteOmniLog(const std::string& path, const std::vector<OmniLogRow>& rows);

// Writes `t,x,y,theta` rows (a replay's output) atomically.
void WritePoseCsv(const std::string& path, const std::vector<double>& t, const std::vector<Pose2>& poses);

}  // namespace twinsim
