// Arm models against a measured log, as MATLAB's `compare` shows them: each source (a
// model on a backend) is simulated open loop from the log's torques (the simulation score
// of analysis/arm_simulation_score.h) at several horizons and as one free run, beside the
// baselines of no model (holding the joints, constant velocity), and its free run is kept
// for the plot of simulated against measured motion (`twinsim compare` for arms,
// docs/identification.md, "Simulation error").
//
//   std::vector<ArmCompareSource> sources = {{"urdf", urdf, "analytic", {}},
//                                            {"identified", identified, "analytic", {}}};
//   ArmCompareResult r = CompareArmLog(log, sources, {});
//   std::printf("%s", r.FullReport().c_str());
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/arm_simulation_score.h"
#include "backends/arm_backend_factory.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// One model on one backend.
struct ArmCompareSource {
  std::string name;     // its label in the tables, CSVs and plots (unique)
  ArmModel model;
  std::string backend = "analytic";  // MakeArmBackend's names
  ArmBackendOptions backend_options;  // e.g. the learned backend's predictor
};

struct ArmCompareOptions {
  // s: the windows' lengths, each restarted from the logged state; 0 is the free run.
  // Those the log is too short for (for any source) are left out.
  std::vector<double> horizons = {0.05, 0.1, 0.25, 0.5, 1, 2, 0};
  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct ArmCompareResult {
  std::vector<std::pair<std::string, ArmSimulationScore>> scores;  // one per source, in order
  // The tables of FormatArmSimulationScores: per horizon and joint, every source beside
  // the baselines, and on how many joints each beats them.
  std::string FullReport() const;
};

// Scores every source on `log` at the horizons all of them fit; `progress` (if set) is
// told (done, total, source name) after each. Throws InputError for bad options, no
// source, two sources of one name, a log of another arm or one too short for any
// window; CheckFailed never (a source that runs away is held and counted).
ArmCompareResult CompareArmLog(const ArmLog& log, const std::vector<ArmCompareSource>& sources,
                               const ArmCompareOptions& options = {},
                               const std::function<void(long, long, const std::string&)>& progress = {});

// paths.csv: t,measured_q1..measured_qn, then <source>_q1..<source>_qn per source with a
// free run (the name's characters other than letters, digits and '_' as '_'): one row per
// log row, the simulated columns empty outside the free run.
std::string FormatArmComparePathsCsv(const ArmLog& log, const ArmCompareResult& result);

// A source name as a CSV column prefix: letters, digits and '_' kept, the rest '_'.
std::string CsvColumnPrefix(const std::string& name);

}  // namespace twinsim
