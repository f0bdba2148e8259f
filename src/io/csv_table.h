// A CSV table with one header row, read with the file, line and column of every value
// kept for error messages. Values are numbers; a column may hold anything else (a robot
// id, a note) as long as nobody asks for it: the first value of each column that is
// not a finite number is remembered, and RequireColumn() reports it. So extra columns,
// numeric or not, are ignored, as CONTRACT.md says of logs.
//
//   CsvTable t = ReadCsvTable("log.csv");
//   int x = t.RequireColumn("x");   // InputError "log.csv:1: missing column 'x' (have: ...)"
//   double v = t.rows[i][x];        // t.line_of[i] is row i's line in the file
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace twinsim {

struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;  // NaN where a value is not a finite number
  std::vector<int> line_of;  // 1-based file line of each row
  // Per column, its first value that is not a finite number (line 0: none).
  struct Problem {
    int line = 0, column = 0;
    std::string message;  // "path:line:col: ..."
  };
  std::vector<Problem> problem;
  // Per column, its first value that is neither a finite number nor empty (line 0:
  // none): what RequireColumns(names, true) reports.
  std::vector<Problem> nonempty_problem;
  // Per column, the text of every row for the label columns (kLabelColumns: a robot id,
  // a team), which may hold words; empty for the other columns.
  std::vector<std::vector<std::string>> label;

  // Index of the column, or -1 (its values unchecked).
  int Column(const std::string& name) const;
  // Index of the column, all of whose values are finite numbers. Throws InputError
  // naming the file and the columns it has, or the first value that is not a number.
  // With allow_empty, empty cells pass (see RequireColumns).
  int RequireColumn(const std::string& name, bool allow_empty = false) const;
  // RequireColumn() for each name; of bad values in the columns there are, the first in
  // the file is reported, before a missing column (as a reader going row by row would).
  // Empty cells pass (they read as NaN) in the columns named in `may_be_empty`: a camera
  // frame without a measurement leaves its pose cells empty.
  std::vector<int> RequireColumns(const std::vector<std::string>& names,
                                  const std::vector<std::string>& may_be_empty = {}) const;
};

// Columns whose text the reader keeps (CsvTable::label), to tell robots apart in a log
// holding several.
inline const char* const kLabelColumns[] = {"robot_id", "robot", "id", "team"};

// The largest CSV file read (1 GiB: days of a robot at 30 fps); larger ones are refused
// before any memory is taken.
inline constexpr std::uintmax_t kMaxCsvBytes = std::uintmax_t{1} << 30;

// Reads a CSV table. Throws InputError "path:line:column: ..." on a missing file, an
// empty file, or a row with the wrong number of fields; text, NaN or infinity where a
// number belongs is reported by RequireColumn(). Blank lines are skipped; a trailing
// '\r' is ignored. A field may be quoted as RFC 4180 writes it ("a, b"; "" for a quote),
// but not across a line break (a quote left open reads as a character).
CsvTable ReadCsvTable(const std::string& path);
CsvTable ParseCsvTable(const std::string& text, const std::string& path);

// A table from numbers held in memory (a NumPy array, a log being built), checked as a
// file would be: `name` stands for the path, row i (0-based) for line i + 1, so messages
// read "NAME:ROW:COLUMN: ..." with 1-based rows and columns. Non-finite values are
// reported by RequireColumn() like text in a file. Throws InputError for a row whose
// length differs from the header's.
CsvTable TableFromRows(const std::string& name, std::vector<std::string> header, std::vector<std::vector<double>> rows);

// Formats a value the way every twinsim CSV does: fixed, enough digits to round-trip
// the simulation's meaningful precision (1e-9), no locale.
std::string FormatCsvNumber(double v);

// A CSV of time series per joint: a `t` column, then for each matrix (rows x joints,
// one row per time) one column per joint named prefix1..prefixn, numbers by
// FormatCsvNumber. All matrices have t.size() rows and the same number of columns.
std::string JointColumnsCsv(const Eigen::VectorXd& t, const std::vector<const char*>& prefixes,
                            const std::vector<const Eigen::MatrixXd*>& columns);

}  // namespace twinsim
