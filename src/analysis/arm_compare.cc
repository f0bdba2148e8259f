#include "analysis/arm_compare.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <set>

#include "core/error.h"
#include "io/csv_table.h"

namespace twinsim {

bool ArmCompareOptions::IsValid(std::string* why) const {
  ArmSimulationScoreOptions score;
  score.horizons = horizons;
  return score.IsValid(why);
}

std::string ArmCompareResult::FullReport() const { return FormatArmSimulationScores(scores); }

std::string CsvColumnPrefix(const std::string& name) {
  std::string prefix = name;
  for (char& c : prefix)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  return prefix;
}

ArmCompareResult CompareArmLog(const ArmLog& log, const std::vector<ArmCompareSource>& sources,
                               const ArmCompareOptions& options,
                               const std::function<void(long, long, const std::string&)>& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("compare: " + why);
  if (sources.empty()) throw InputError("compare: no model to compare");
  std::set<std::string> names, prefixes;
  for (const ArmCompareSource& s : sources) {
    if (!names.insert(s.name).second) throw InputError("compare: two sources are called '" + s.name + "'");
    if (!prefixes.insert(CsvColumnPrefix(s.name)).second)
      throw InputError("compare: two sources' names give the CSV columns '" + CsvColumnPrefix(s.name) + "_q1'");
    CheckArmLogMatchesModel(log, s.model);
  }
  // The horizons every source fits (their delays shift the first window), so that the
  // tables line up; a log too short for any is refused by the score itself.
  ArmSimulationScoreOptions score;
  score.horizons.clear();
  for (double h : options.horizons) {
    bool fits = true;
    for (const ArmCompareSource& s : sources) {
      int length = 0;
      fits = fits && !ArmSimulationWindows(ArmModelAtLogPeriod(s.model, log.sample_period), log, h, &length).empty();
    }
    if (fits) score.horizons.push_back(h);
  }
  if (score.horizons.empty()) score.horizons = {options.horizons.front()};  // its message says why

  ArmCompareResult result;
  long done = 0;
  for (const ArmCompareSource& s : sources) {
    score.backend = s.backend;
    score.backend_options = s.backend_options;
    result.scores.emplace_back(s.name, ScoreArmSimulation(s.model, log, score));
    if (progress) progress(++done, static_cast<long>(sources.size()), s.name);
  }
  return result;
}

std::string FormatArmComparePathsCsv(const ArmLog& log, const ArmCompareResult& result) {
  const int n = log.dof;
  std::string csv = "t";
  for (int j = 1; j <= n; ++j) csv += ",measured_q" + std::to_string(j);
  std::vector<const ArmSimulationScore*> runs;
  for (const auto& [name, score] : result.scores) {
    if (score.free_run_start < 0) continue;
    runs.push_back(&score);
    for (int j = 1; j <= n; ++j) csv += "," + CsvColumnPrefix(name) + "_q" + std::to_string(j);
  }
  csv += "\n";
  for (int i = 0; i < log.rows(); ++i) {
    csv += FormatCsvNumber(log.t[i]);
    for (int j = 0; j < n; ++j) csv += "," + FormatCsvNumber(log.q(i, j));
    for (const ArmSimulationScore* run : runs) {
      const int r = i - run->free_run_start - 1;
      const bool inside = r >= 0 && r < run->free_run.rows();
      for (int j = 0; j < n; ++j) csv += "," + (inside ? FormatCsvNumber(run->free_run(r, j)) : std::string());
    }
    csv += "\n";
  }
  return csv;
}

}  // namespace twinsim
