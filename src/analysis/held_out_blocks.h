// Held-out blocks: a log's time cut into blocks, some fitted on and some held out, so
// that what a fit chooses is judged on data it never saw (identify, diagnose). A share
// of the blocks is held out, spread over the log and never periodic; the held-out blocks
// alternate between selection (choose) and test (report, choose nothing), and rows near
// a boundary between kinds are guards, used by nothing.
//
//   const double block = HeldOutBlockSeconds(options.block_seconds, durations);
//   CheckLogHoldsOut(t, 0, block, 0.4, log.path);           // InputError when too short
//   if (InHeldOutBlock(t[i], block, 0.4)) ...               // not fitted on
//   switch (HeldOutRowKind(t[i], block, 0.4, guard)) ...    // fit, selection, test, guard
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace twinsim {

struct ArmLog;

// The block length (s) for logs of these durations (s): `block_seconds` where it is
// positive, else a twentieth of the longest log, within 0.5..10 s.
double HeldOutBlockSeconds(double block_seconds, const std::vector<double>& durations);

// What a residual row is for. The held-out blocks (InHeldOutBlock) alternate between
// selection (the 1st, 3rd, ... held-out block: choose the effects) and test (the 2nd,
// 4th, ...: report the gaps, choose nothing). Rows within `guard` s of a boundary
// between blocks of different kinds are guards, used by nothing: a zero-phase filter's
// derivatives and a prediction's start reach across a boundary by about that much.
enum class RowKind : char { kFit, kSelection, kTest, kGuard };
RowKind HeldOutRowKind(double t, double block_seconds, double held_out, double guard_seconds);

// The block (0, 1, ...) the sample at time t (s from the log's start) lies in.
int TimeBlockIndex(double t, double block_seconds);

// Whether the sample at time t (s from the log's start) lies in a held-out block:
// blocks k = floor(t / block) >= 1 are held out where frac(k g) < h, g = (sqrt 5 - 1) / 2,
// the first block always kept for fitting. A Weyl sequence: a share h of the blocks,
// spread over the log (gaps of two or three sizes), and never periodic, so the held-out
// blocks cannot line up with a periodic excitation (an evenly repeating pattern, every
// 5th block for h = 0.4, put the selection blocks of a 10 s Fourier excitation cut into
// 1 s blocks on 2 phases of it; issue 41).
bool InHeldOutBlock(double t, double block_seconds, double held_out);

// Throws InputError "path:1: ..." unless the times `t` (s, from `first` on; the rows a
// residual exists for) span at least two held-out and two fit blocks.
void CheckLogHoldsOut(const std::vector<double>& t, std::size_t first, double block_seconds, double held_out,
                      const std::string& path);

// The rows of arm `logs` outside the held-out blocks (InHeldOutBlock) and each log's
// edge_samples, one log per contiguous stretch of at least 3 rows (edge_samples 0):
// what an identification may fit on while the held-out blocks judge it.
std::vector<ArmLog> ArmFitBlockLogs(const std::vector<ArmLog>& logs, double block_seconds, double held_out);

}  // namespace twinsim
