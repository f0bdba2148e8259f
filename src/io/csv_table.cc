#include "io/csv_table.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace twinsim {
namespace {

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    std::size_t comma = line.find(',', start);
    std::string f = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    // Trim spaces around the field.
    const std::size_t a = f.find_first_not_of(" \t");
    const std::size_t b = f.find_last_not_of(" \t");
    out.push_back(a == std::string::npos ? std::string() : f.substr(a, b - a + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

int CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

int CsvTable::RequireColumn(const std::string& name) const {
  const int c = Column(name);
  if (c >= 0) return c;
  std::string have;
  for (const auto& h : header) have += (have.empty() ? "" : ", ") + h;
  throw InputError(SourceLocation{path, 1}, "missing column '" + name + "' (have: " + have + ")");
}

CsvTable ParseCsvTable(const std::string& text, const std::string& path) {
  CsvTable t;
  t.path = path;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    std::vector<std::string> fields = SplitFields(line);
    if (!have_header) {
      t.header = fields;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i].empty())
          throw InputError(SourceLocation{path, line_no, 0}, "empty column name in the header (column " + std::to_string(i + 1) + ")");
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
    int column = 1;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const std::string& f = fields[i];
      double v = 0;
      const char* begin = f.data();
      const char* end = f.data() + f.size();
      if (!f.empty() && *begin == '+') ++begin;
      auto [ptr, ec] = std::from_chars(begin, end, v);
      if (f.empty() || ec != std::errc() || ptr != end) {
        throw InputError(SourceLocation{path, line_no, column},
                         "column '" + t.header[i] + "': expected a number, got '" + f + "'");
      }
      if (!std::isfinite(v)) {
        throw InputError(SourceLocation{path, line_no, column},
                         "column '" + t.header[i] + "': value is " + f + ", not a finite number");
      }
      row[i] = v;
      column += static_cast<int>(f.size()) + 1;
    }
    t.rows.push_back(std::move(row));
    t.line_of.push_back(line_no);
  }
  if (!have_header) throw InputError(SourceLocation{path, 1}, "empty file: expected a header row");
  return t;
}

CsvTable ReadCsvTable(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(SourceLocation{path}, "cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseCsvTable(buffer.str(), path);
}

std::string FormatCsvNumber(double v) {
  char buf[64];
  if (v == 0) v = 0;  // no "-0.000000000"
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

}  // namespace twinsim
