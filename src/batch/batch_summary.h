// What a sweep leaves behind besides its job folders: each job's result.json (written
// last into its folder, so a folder with one is complete), DIR/summary.csv (one row per
// job) and DIR/summary.html (the metrics plotted against the swept parameters).
//
// summary.csv: job,seed,<swept parameters>,status,wall_s,<metrics>,error. Metrics are
// the union over jobs in order of first appearance (a failed job's cells are empty);
// numbers print with 10 significant digits. Only wall_s differs between two runs of
// the same sweep.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "batch/batch_job.h"
#include "batch/sweep.h"

namespace twinsim {

// result.json of a job: its id, seed, parameters (as written in the sweep), status,
// error, wall time and metrics.
std::string FormatJobResultJson(const SweepJob& job, const JobResult& result);
// Reads result.json text back for `job`; nullopt when it is not valid JSON, belongs to
// another job or other parameters (a changed sweep), so that the job runs again.
std::optional<JobResult> ParseJobResultJson(const std::string& text, const SweepJob& job);

std::string FormatSummaryCsv(const Sweep& sweep, const std::vector<SweepJob>& jobs,
                             const std::vector<JobResult>& results);
// A self-contained page: counts, failures, and per metric a plot against every numeric
// swept parameter (one series per value of the other swept parameters). Plots only
// where rendering was compiled in.
std::string FormatSummaryHtml(const Sweep& sweep, const std::vector<SweepJob>& jobs,
                              const std::vector<JobResult>& results);

}  // namespace twinsim
