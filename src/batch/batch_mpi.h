// The batch runner's parts shared by its thread and MPI paths (batch_runner.cc,
// batch_mpi.cc). Internal to src/batch/.
#pragma once

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "batch/batch_job.h"
#include "batch/batch_runner.h"
#include "batch/sweep.h"
#include "core/progress.h"

namespace twinsim::batch_internal {

// Runs `job` into its folder (emptied first) and writes result.json last; returns its text.
std::string RunJobIntoFolder(const Sweep& sweep, const SweepJob& job, const BatchOptions& options, JobResult* result);

// Checks and records the output folder; the jobs still to run (complete ones' results filled in).
std::vector<int> PrepareFolder(const Sweep& sweep, const std::vector<SweepJob>& jobs, const BatchOptions& options,
                               std::vector<JobResult>* results, int* resumed);

// Writes summary.csv and summary.html; counts the failures into *summary.
void WriteSummary(const Sweep& sweep, const std::vector<SweepJob>& jobs, const std::vector<JobResult>& results,
                  const BatchOptions& options, BatchSummary* summary);

// `threads` workers, each running `run(job)` for every job `next()` gives until it
// gives none. Rethrows the first exception of a worker after all stopped.
void RunLocalWorkers(int threads, const std::function<std::optional<int>()>& next, const std::function<void(int)>& run);

// Progress of a sweep on stderr: a live line on a terminal, plain lines in a log.
class BatchReporter {
 public:
  BatchReporter(const Sweep& sweep, int total, int already_done, int already_failed, bool enabled);
  void JobDone(bool failed);  // thread-safe
  void Finish();

 private:
  std::mutex mutex_;
  Progress progress_;
  std::string name_;
  int total_, done_, failed_, ran_ = 0;
  bool plain_;
  std::chrono::steady_clock::time_point start_, last_plain_;
};

// The sweep across MPI ranks (batch_mpi.cc); only called when MpiCompiled().
BatchSummary RunBatchMpi(const Sweep& sweep, const std::vector<SweepJob>& jobs, const BatchOptions& options);

}  // namespace twinsim::batch_internal
