#include "batch/batch_runner.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "batch/batch_mpi.h"
#include "batch/batch_summary.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "io/atomic_file.h"
#include "io/output_transaction.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  return *end == '\0' && x >= 0 && x < 1000000 ? static_cast<int>(x) : fallback;
}

int LauncherSize() {
  for (const char* n : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"}) {
    const int v = EnvInt(n, -1);
    if (v >= 0) return v;
  }
  return 1;
}

int LauncherRank() {
  for (const char* n : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"}) {
    const int v = EnvInt(n, -1);
    if (v >= 0) return v;
  }
  return 0;
}

// FNV-1a over what makes the sweep's jobs what they are.
std::string Fingerprint(const Sweep& sweep, const std::vector<SweepJob>& jobs) {
  std::uint64_t h = 1469598103934665603ull;
  const auto add = [&](const std::string& s) {
    for (unsigned char c : s) {
      h ^= c;
      h *= 1099511628211ull;
    }
    h ^= 0xff;
    h *= 1099511628211ull;
  };
  add(sweep.command);
  add(sweep.plots ? "plots" : "");
  for (const SweepJob& job : jobs) {
    add(job.id);
    add(std::to_string(job.seed));
    for (const auto& [name, value] : job.parameters) {
      add(name);
      add(value.text);
    }
  }
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string ReadSmallFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string JobFolder(const BatchOptions& options, const SweepJob& job) { return options.out + "/jobs/" + job.id; }

// Checks that `out` may take this sweep and records it there; returns the jobs still to
// run, with the results of complete folders (--resume) filled in.
std::vector<int> Prepare(const Sweep& sweep, const std::vector<SweepJob>& jobs, const BatchOptions& options,
                         std::vector<JobResult>* results, int* resumed) {
  const std::string record = options.out + "/batch.json";
  const std::string fingerprint = Fingerprint(sweep, jobs);
  // The name as a JSON string (escaped: a sweep may be named anything YAML holds).
  const std::string expected = "{\"sweep\": " + nlohmann::json(sweep.name).dump() + ", \"jobs\": " +
                               std::to_string(jobs.size()) + ", \"fingerprint\": \"" + fingerprint + "\"}\n";
  std::error_code ec;
  const bool has_record = fs::exists(record, ec);
  if (!options.resume && (has_record || fs::exists(options.out + "/jobs", ec))) {
    throw InputError(options.out + ": already holds a sweep; add --resume to continue it, or choose another --out");
  }
  if (options.resume && has_record && ReadSmallFile(record) != expected) {
    throw InputError(options.out + ": holds another sweep (" + record +
                     " differs: the sweep file or its jobs changed); choose another --out");
  }
  WriteFileAtomically(record, expected);
  std::vector<int> pending;
  for (const SweepJob& job : jobs) {
    const std::string folder = JobFolder(options, job);
    if (options.resume && fs::exists(folder + "/result.json", ec)) {
      std::optional<JobResult> r = ParseJobResultJson(ReadSmallFile(folder + "/result.json"), job);
      if (r) {
        (*results)[job.index] = *r;
        ++*resumed;
        continue;
      }
    }
    pending.push_back(job.index);
  }
  return pending;
}

}  // namespace

namespace batch_internal {

std::string RunJobIntoFolder(const Sweep& sweep, const SweepJob& job, const BatchOptions& options,
                             JobResult* result) {
  const std::string folder = JobFolder(options, job);
  // A job's folder is complete when its result.json, written last, is there; it is
  // written at once even under the command's output transaction, so that --resume keeps
  // the jobs that finished.
  OutputTransactionPause direct_writes;
  std::error_code ec;
  fs::remove_all(folder, ec);  // what an interrupted run left is never taken as complete
  fs::create_directories(folder, ec);
  try {
    *result = RunSweepJob(sweep, job, folder);
  } catch (const Interrupted&) {
    fs::remove_all(folder, ec);
    throw;
  }
  const std::string json = FormatJobResultJson(job, *result);
  WriteFileAtomically(folder + "/result.json", json);
  return json;
}

BatchReporter::BatchReporter(const Sweep& sweep, int total, int already_done, int already_failed, bool enabled)
    : progress_("batch " + sweep.name, enabled),
      name_(sweep.name),
      total_(total),
      done_(already_done),
      failed_(already_failed),
      plain_(enabled && !::isatty(2)),
      start_(std::chrono::steady_clock::now()),
      last_plain_(start_) {}

void BatchReporter::JobDone(bool failed) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++done_;
  ++ran_;
  failed_ += failed;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double left = ran_ > 0 ? elapsed / ran_ * (total_ - done_) : 0;
  char detail[160];
  std::snprintf(detail, sizeof detail, "%d/%d jobs, %d failed, %.0f s left", done_, total_, failed_, left);
  progress_.Update(done_, total_, detail);
  // In a log: a line every tenth of the sweep or every 30 s, and at the end.
  const int tenth = std::max(1, total_ / 10);
  if (plain_ && (done_ == total_ || done_ % tenth == 0 || now - last_plain_ > std::chrono::seconds(30))) {
    last_plain_ = now;
    std::fprintf(stderr, "batch %s: %s\n", name_.c_str(), detail);
    std::fflush(stderr);
  }
}

void BatchReporter::Finish() { progress_.Finish(); }

void RunLocalWorkers(int threads, const std::function<std::optional<int>()>& next,
                     const std::function<void(int)>& run) {
  std::vector<std::thread> workers;
  std::mutex error_mutex;
  std::exception_ptr error;
  for (int w = 0; w < threads; ++w) {
    workers.emplace_back([&] {
      try {
        while (const std::optional<int> job = next()) {
          ThrowIfInterrupted();
          run(*job);
        }
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    });
  }
  for (std::thread& t : workers) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace batch_internal

bool BatchOptions::IsValid(std::string* why) const {
  std::string problems;
  if (out.empty()) problems += "the output folder is empty\n";
  if (jobs < 0 || jobs > 4096) problems += "jobs must be 0 (one per core) to 4096, got " + std::to_string(jobs) + "\n";
  if (why) *why = problems.empty() ? "" : problems.substr(0, problems.size() - 1);
  return problems.empty();
}

std::string BatchSummary::BriefReport() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%d jobs: %d ran, %d resumed, %d failed; %d rank(s) x %d thread(s), %.2f s wall",
                jobs, ran, resumed, failed, ranks, threads, wall_s);
  return buf;
}

std::string BatchSummary::FullReport() const {
  std::string s = BriefReport() + "\n";
  if (ran > 0) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "throughput: %.1f jobs per second\n", wall_s > 0 ? ran / wall_s : 0.0);
    s += buf;
  }
  if (!written.empty()) {
    s += "wrote:\n";
    for (const std::string& w : written) s += "  " + w + "\n";
  }
  return s;
}

bool StartedUnderMpi() { return LauncherSize() > 1; }

BatchSummary RunBatch(const Sweep& sweep, const BatchOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("batch: " + why);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<SweepJob> jobs = ExpandSweep(sweep);
  BatchSummary summary;
  summary.jobs = static_cast<int>(jobs.size());
  CheckSweepJobLoads(sweep, jobs.front());

  if (StartedUnderMpi() && MpiCompiled()) return batch_internal::RunBatchMpi(sweep, jobs, options);
  if (StartedUnderMpi()) {
    if (LauncherRank() != 0) {
      summary.writer = false;
      return summary;  // rank 0 runs the whole sweep on its threads
    }
    std::fprintf(stderr, "batch: started by an MPI launcher, but this build has no MPI (install libopenmpi-dev and "
                         "rebuild); rank 0 runs every job on this machine's threads, the other ranks stop\n");
  }

  std::vector<JobResult> results(jobs.size());
  const std::vector<int> pending = Prepare(sweep, jobs, options, &results, &summary.resumed);
  int failed_before = 0;
  for (const JobResult& r : results) failed_before += r.status == "failed";
  summary.threads = std::min<int>(ResolveThreadCount(options.jobs), std::max<int>(1, pending.size()));
  batch_internal::BatchReporter reporter(sweep, summary.jobs, summary.resumed, failed_before, options.progress);
  std::atomic<std::size_t> cursor{0};
  batch_internal::RunLocalWorkers(
      summary.threads,
      [&]() -> std::optional<int> {
        const std::size_t k = cursor++;
        if (k >= pending.size()) return std::nullopt;
        return pending[k];
      },
      [&](int index) {
        JobResult r;
        batch_internal::RunJobIntoFolder(sweep, jobs[index], options, &r);
        results[index] = r;
        reporter.JobDone(r.status != "ok");
      });
  reporter.Finish();
  summary.ran = static_cast<int>(pending.size());
  batch_internal::WriteSummary(sweep, jobs, results, options, &summary);
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

namespace batch_internal {

std::vector<int> PrepareFolder(const Sweep& sweep, const std::vector<SweepJob>& jobs, const BatchOptions& options,
                               std::vector<JobResult>* results, int* resumed) {
  return Prepare(sweep, jobs, options, results, resumed);
}

void WriteSummary(const Sweep& sweep, const std::vector<SweepJob>& jobs, const std::vector<JobResult>& results,
                  const BatchOptions& options, BatchSummary* summary) {
  summary->failed = 0;
  for (const JobResult& r : results) summary->failed += r.status != "ok";
  WriteFileAtomically(options.out + "/summary.csv", FormatSummaryCsv(sweep, jobs, results));
  WriteFileAtomically(options.out + "/summary.html", FormatSummaryHtml(sweep, jobs, results));
  summary->written = {options.out + "/summary.csv", options.out + "/summary.html"};
}

}  // namespace batch_internal

}  // namespace twinsim
