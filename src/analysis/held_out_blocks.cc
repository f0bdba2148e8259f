#include "analysis/held_out_blocks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "core/error.h"
#include "robots/arm/arm_log.h"

namespace twinsim {

double HeldOutBlockSeconds(double block_seconds, const std::vector<double>& durations) {
  if (block_seconds > 0) return block_seconds;
  double longest = 0;
  for (double d : durations) longest = std::max(longest, d);
  return std::clamp(longest / 20, 0.5, 10.0);
}

int TimeBlockIndex(double t, double block_seconds) {
  return static_cast<int>(std::floor(std::max(0.0, t) / block_seconds));
}

namespace {

// The golden ratio's fractional part, (sqrt 5 - 1) / 2: block k is held out where
// frac(k g) < h (a Weyl sequence: equidistributed, never periodic).
constexpr double kGoldenFraction = 0.6180339887498948482;

bool IsHeldOutBlock(long k, double held_out) {
  if (k < 1) return false;  // the first block is always kept for fitting
  const double x = static_cast<double>(k) * kGoldenFraction;
  return x - std::floor(x) < held_out;
}

}  // namespace

bool InHeldOutBlock(double t, double block_seconds, double held_out) {
  return IsHeldOutBlock(TimeBlockIndex(t, block_seconds), held_out);
}

RowKind HeldOutRowKind(double t, double block_seconds, double held_out, double guard_seconds) {
  auto kind_at = [&](double u) {
    const long k = TimeBlockIndex(u, block_seconds);  // before the log: as its first block
    if (!IsHeldOutBlock(k, held_out)) return RowKind::kFit;
    long before = 0;  // held-out blocks before block k
    for (long j = 1; j < k; ++j) before += IsHeldOutBlock(j, held_out) ? 1 : 0;
    return before % 2 == 0 ? RowKind::kSelection : RowKind::kTest;
  };
  const RowKind here = kind_at(t);
  const double guard = std::min(guard_seconds, 0.45 * block_seconds);
  if (guard > 0 && (kind_at(t - guard) != here || kind_at(t + guard) != here)) return RowKind::kGuard;
  return here;
}

void CheckLogHoldsOut(const std::vector<double>& t, std::size_t first, double block_seconds, double held_out,
                      const std::string& path) {
  std::set<long> held, fit;
  for (std::size_t i = first; i < t.size(); ++i) {
    const long k = TimeBlockIndex(t[i] - t.front(), block_seconds);
    (IsHeldOutBlock(k, held_out) ? held : fit).insert(k);
  }
  if (held.size() < 2 || fit.size() < 2) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "the log is %.3g s long: too short to hold out two %.3g s blocks for checking beside two for fitting "
                  "(give a longer log, or a shorter --block)",
                  t.empty() ? 0.0 : t.back() - t.front(), block_seconds);
    throw InputError(SourceLocation{path, 1}, msg);
  }
}

std::vector<ArmLog> ArmFitBlockLogs(const std::vector<ArmLog>& logs, double block, double held_out) {
  std::vector<ArmLog> parts;
  for (const ArmLog& log : logs) {
    int r = log.edge_samples;
    const int end = log.rows() - log.edge_samples;
    while (r < end) {
      while (r < end && InHeldOutBlock(log.t[r] - log.t[0], block, held_out)) ++r;
      const int first = r;
      while (r < end && !InHeldOutBlock(log.t[r] - log.t[0], block, held_out)) ++r;
      const int rows = r - first;
      if (rows < 3) continue;
      ArmLog part = log;
      part.t = log.t.segment(first, rows);
      part.q = log.q.middleRows(first, rows);
      part.qd = log.qd.middleRows(first, rows);
      part.qdd = log.qdd.middleRows(first, rows);
      part.tau = log.tau.middleRows(first, rows);
      if (log.qref.rows() > 0) part.qref = log.qref.middleRows(first, rows);
      if (static_cast<int>(log.line_of.size()) == log.rows()) {
        part.line_of.assign(log.line_of.begin() + first, log.line_of.begin() + first + rows);
      } else {
        part.line_of.clear();  // a log made in memory has no file lines
      }
      part.edge_samples = 0;
      parts.push_back(std::move(part));
    }
  }
  return parts;
}

}  // namespace twinsim
