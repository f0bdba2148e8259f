// The diagnosis report as users read it: report.json (CONTRACT.md, with extra keys),
// report.html (one self-contained file: the verdict, the residual before and after,
// against velocity, its spectrum, every candidate tried, and for omni robots the
// measured, nominal and repaired paths) and a short table for the terminal.
//
//   WriteFileAtomically(dir + "/report.json", FormatDiagnosisJson(report));
//   WriteFileAtomically(dir + "/report.html", FormatDiagnosisHtml(report, *MakeDefaultRenderer()));
//   std::fputs(FormatDiagnosisTable(report).c_str(), stdout);
#pragma once

#include <string>

#include "diagnosis/diagnosis.h"
#include "render/renderer.h"

namespace twinsim {

// The verdict in one line: "nothing significant is missing" or the effects named with
// the gap before and after.
std::string DiagnosisVerdict(const DiagnosisReport& report);

// report.json: the contract's keys (robot, metric, gap_before, gap_after, effects with
// name, joint 1-based or null, parameters, gap_reduction, evidence) plus model,
// noise_floor, fit gaps, the held-out split, candidates, findings and notes. The same
// report gives the same bytes.
std::string FormatDiagnosisJson(const DiagnosisReport& report);

// report.html with its plots embedded as PNG (data: URLs), drawn by `renderer`.
std::string FormatDiagnosisHtml(const DiagnosisReport& report, Renderer& renderer);

// The terminal's summary: verdict, gaps, effects, and the best candidates per round.
std::string FormatDiagnosisTable(const DiagnosisReport& report);

}  // namespace twinsim
