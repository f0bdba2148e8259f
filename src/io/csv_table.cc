#include "io/csv_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "core/error.h"
#include "io/input_file.h"

namespace twinsim {
namespace {

struct Field {
  std::string text;  // trimmed, quotes removed
  int column = 1;    // 1-based character column where the text starts
};

// The fields of one line. A field may be quoted as RFC 4180 writes it ("a note, with a
// comma", "" for a quote inside), so that a logger's text columns pass; as Python's
// csv module reads them, text after the closing quote joins the field ("Fast" run is
// Fast run), and a quote that does not open a field (5", it's) is a character. A quote
// left open to the line's end (a line break inside quotes, which lines read one by one
// cannot follow) reads the field as if unquoted, quote and all: nothing a reader that
// split at every comma took is refused.
std::vector<Field> SplitFields(const std::string& line) {
  std::vector<Field> out;
  std::size_t start = 0;
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  auto trim = [&](std::string text) {
    std::size_t a = 0, b = text.size();
    while (a < b && blank(text[a])) ++a;
    while (b > a && blank(text[b - 1])) --b;
    return text.substr(a, b - a);
  };
  while (true) {
    std::size_t a = start;
    while (a < line.size() && blank(line[a])) ++a;
    const std::size_t close = a < line.size() && line[a] == '"' ? line.find('"', a + 1) : std::string::npos;
    if (close != std::string::npos) {
      std::string text;
      std::size_t i = a + 1;
      while (i < line.size()) {  // inside the quotes; `""` is a quote
        if (line[i] != '"') {
          text += line[i++];
        } else if (i + 1 < line.size() && line[i + 1] == '"') {
          text += '"';
          i += 2;
        } else {
          break;
        }
      }
      if (i < line.size()) {  // closed: the rest up to the next comma joins the field
        const std::size_t comma = line.find(',', i + 1);
        text += line.substr(i + 1, (comma == std::string::npos ? line.size() : comma) - (i + 1));
        out.push_back(Field{trim(text), static_cast<int>(a) + 1});
        if (comma == std::string::npos) break;
        start = comma + 1;
        continue;
      }
      // Open to the line's end ("" pairs only): read as unquoted below.
    }
    const std::size_t comma = line.find(',', start);
    const std::size_t stop = comma == std::string::npos ? line.size() : comma;
    std::size_t b = stop;
    while (b > a && blank(line[b - 1])) --b;
    out.push_back(Field{line.substr(a, b - a), static_cast<int>(a) + 1});
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// A field as quoted in a message: a 20,000-digit "number" is cut.
std::string Clip(const std::string& field) {
  return field.size() <= 40 ? field : field.substr(0, 37) + "...";
}

}  // namespace

int CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

int CsvTable::RequireColumn(const std::string& name, bool allow_empty) const {
  const int c = Column(name);
  if (c >= 0) {
    for (std::size_t k = static_cast<std::size_t>(c) + 1; k < header.size(); ++k) {
      if (header[k] == name) {
        throw InputError(SourceLocation{path, 1}, "column '" + name + "' appears twice (columns " +
                                                      std::to_string(c + 1) + " and " + std::to_string(k + 1) +
                                                      "): which one holds the data?");
      }
    }
    const Problem& p = (allow_empty ? nonempty_problem : problem)[static_cast<std::size_t>(c)];
    if (p.line > 0) throw InputError(p.message);
    return c;
  }
  std::string have;
  for (const auto& h : header) have += (have.empty() ? "" : ", ") + h;
  throw InputError(SourceLocation{path, 1}, "missing column '" + name + "' (have: " + have + ")");
}

std::vector<int> CsvTable::RequireColumns(const std::vector<std::string>& names,
                                          const std::vector<std::string>& may_be_empty) const {
  std::vector<int> columns;
  const Problem* first = nullptr;
  const std::string* missing = nullptr;
  for (const std::string& name : names) {
    const int c = Column(name);
    columns.push_back(c);
    const bool allow_empty = std::find(may_be_empty.begin(), may_be_empty.end(), name) != may_be_empty.end();
    if (c >= 0) RequireColumn(name, allow_empty);  // throws for a column given twice
    if (c < 0) {
      if (!missing) missing = &name;
      continue;
    }
    const Problem& p = (allow_empty ? nonempty_problem : problem)[static_cast<std::size_t>(c)];
    if (p.line > 0 && (!first || std::tie(p.line, p.column) < std::tie(first->line, first->column))) first = &p;
  }
  // A bad value is named before a missing column, as a reader going row by row would.
  if (first) throw InputError(first->message);
  if (missing) RequireColumn(*missing);  // throws, listing the columns there are
  return columns;
}

CsvTable TableFromRows(const std::string& name, std::vector<std::string> header, std::vector<std::vector<double>> rows) {
  CsvTable t;
  t.path = name;
  t.header = std::move(header);
  t.problem.assign(t.header.size(), {});
  t.nonempty_problem.assign(t.header.size(), {});
  t.label.assign(t.header.size(), {});
  t.rows = std::move(rows);
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const int line = static_cast<int>(r) + 1;
    t.line_of.push_back(line);
    if (t.rows[r].size() != t.header.size()) {
      throw InputError(SourceLocation{name, line}, "row has " + std::to_string(t.rows[r].size()) + " values, expected " +
                                                       std::to_string(t.header.size()));
    }
    for (std::size_t c = 0; c < t.header.size(); ++c) {
      const double v = t.rows[r][c];
      CsvTable::Problem& problem = t.problem[c];
      if (!std::isfinite(v) && problem.line == 0) {
        std::ostringstream value;
        value << v;
        problem = {line, static_cast<int>(c) + 1,
                   SourceLocation{name, line, static_cast<int>(c) + 1}.Prefix() + "column '" + t.header[c] +
                       "': value is " + value.str() + ", not a finite number"};
        t.nonempty_problem[c] = problem;  // a number held in memory is never an empty cell
      }
    }
  }
  return t;
}

CsvTable ParseCsvTable(const std::string& text, const std::string& path) {
  CsvTable t;
  t.path = path;
  // A UTF-8 byte-order mark, as spreadsheet programs write it, is not part of the header.
  const std::size_t bom = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  std::istringstream in(text.substr(bom));
  std::string line;
  int line_no = 0;
  bool have_header = false;
  std::vector<bool> keep_label;  // per column
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    const std::vector<Field> fields = SplitFields(line);
    if (!have_header) {
      for (const Field& f : fields) {
        if (f.text.empty())
          throw InputError(SourceLocation{path, line_no, f.column}, "empty column name in the header");
        for (const char c : f.text) {
          if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
            throw InputError(SourceLocation{path, line_no, f.column},
                             "the header holds control characters: not a CSV text file?");
          }
        }
        t.header.push_back(f.text);
      }
      t.problem.assign(t.header.size(), {});
      t.nonempty_problem.assign(t.header.size(), {});
      t.label.assign(t.header.size(), {});
      keep_label.assign(t.header.size(), false);
      for (std::size_t c = 0; c < t.header.size(); ++c) {
        for (const char* name : kLabelColumns) keep_label[c] = keep_label[c] || t.header[c] == name;
      }
      have_header = true;
      continue;
    }
    if (fields.size() != t.header.size()) {
      throw InputError(SourceLocation{path, line_no},
                       "expected " + std::to_string(t.header.size()) + " fields like the header, got " +
                           std::to_string(fields.size()));
    }
    std::vector<double> row(fields.size());
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const std::string& f = fields[i].text;
      const int column = fields[i].column;
      double v = 0;
      const char* begin = f.data();
      const char* end = f.data() + f.size();
      if (!f.empty() && *begin == '+') ++begin;
      auto [ptr, ec] = std::from_chars(begin, end, v);
      CsvTable::Problem& problem = t.problem[i];
      const bool text = f.empty() || ec != std::errc() || ptr != end;
      if (text || !std::isfinite(v)) {
        if (problem.line == 0 || (!f.empty() && t.nonempty_problem[i].line == 0)) {
          const CsvTable::Problem found{
              line_no, column,
              SourceLocation{path, line_no, column}.Prefix() + "column '" + t.header[i] + "': " +
                  (f.empty() ? std::string("empty cell where a number belongs")
                   : text    ? "expected a number, got '" + Clip(f) + "'"
                             : "value is " + Clip(f) + ", not a finite number")};
          if (problem.line == 0) problem = found;
          if (!f.empty() && t.nonempty_problem[i].line == 0) t.nonempty_problem[i] = found;
        }
        v = std::numeric_limits<double>::quiet_NaN();
      }
      row[i] = v;
      if (keep_label[i]) t.label[i].push_back(f);
    }
    t.rows.push_back(std::move(row));
    t.line_of.push_back(line_no);
  }
  if (!have_header) throw InputError(SourceLocation{path, 1}, "empty file: expected a header row");
  return t;
}

CsvTable ReadCsvTable(const std::string& path) {
  return ParseCsvTable(ReadInputFile(path, "CSV", kMaxCsvBytes), path);
}

std::string FormatCsvNumber(double v) {
  // A NaN or infinity in an output is a bug upstream (every reader and simulation checks
  // for them), never something to hand on to the next tool.
  if (!std::isfinite(v)) throw std::logic_error("a non-finite number (" + std::to_string(v) + ") reached a CSV writer");
  char buf[64];
  if (v == 0) v = 0;  // no "-0.000000000"
  // Nine decimals (nanometres, nanoseconds) for the numbers a robot produces; beyond
  // 1e15 that would print digits that are not there, so the shortest exact form instead.
  if (std::abs(v) >= 1e15) {
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.9f", v);
  // Trim trailing zeros to keep files small; deterministic for a given double.
  std::string s(buf);
  const std::size_t dot = s.find('.');
  if (dot != std::string::npos) {
    std::size_t last = s.find_last_not_of('0');
    if (last == dot) last = dot - 1;
    s.erase(last + 1);
  }
  if (s == "-0") s = "0";
  return s;
}

std::string JointColumnsCsv(const Eigen::VectorXd& t, const std::vector<const char*>& prefixes,
                            const std::vector<const Eigen::MatrixXd*>& columns) {
  const Eigen::Index n = columns.front()->cols();
  std::string out = "t";
  for (const char* prefix : prefixes) {
    for (Eigen::Index j = 1; j <= n; ++j) {
      out += ',';
      out += prefix;
      out += std::to_string(j);
    }
  }
  out += '\n';
  for (Eigen::Index r = 0; r < t.size(); ++r) {
    out += FormatCsvNumber(t[r]);
    for (const Eigen::MatrixXd* m : columns) {
      for (Eigen::Index j = 0; j < n; ++j) {
        out += ',';
        out += FormatCsvNumber((*m)(r, j));
      }
    }
    out += '\n';
  }
  return out;
}

}  // namespace twinsim
