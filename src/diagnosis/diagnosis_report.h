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

// The verdict in a few sentences: the effects named (or none) with the test-row gap
// before and after and the noise floor; what is left unexplained (where a learned
// residual still predicts part of it: channel, band, what it correlates with); and the
// share of the predictable gap the named physics explains.
std::string DiagnosisVerdict(const DiagnosisReport& report);
// Omni: the report horizons at which the written (repaired) model predicts the test rows
// worse than the given one by more than `tolerance` of the given's error, as one sentence
// with the numbers for DiagnosisReport::caution; "" where it is nowhere worse.
std::string WorseThanGiven(const DiagnosisReport& report, double tolerance);

// Every rule the selection and the adequacy checks followed, with the numbers used.
std::string DiagnosisMethod(const DiagnosisReport& report);

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
