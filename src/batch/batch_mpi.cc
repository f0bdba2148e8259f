// The sweep across MPI ranks. Only the main thread of each rank calls MPI
// (MPI_THREAD_FUNNELED): rank 0's main thread answers requests for jobs and collects
// results while its worker threads run jobs too; on every other rank the main thread
// forwards its workers' requests and results. Messages: a request (an int), a job
// number in reply (-1: none left), a result ("INDEX\n" + result.json), and a last
// "finished" from each rank.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <thread>

#include "batch/batch_mpi.h"
#include "batch/batch_summary.h"
#include "core/error.h"
#include "core/parallel.h"

#if TWINSIM_HAVE_MPI
#include <mpi.h>
#endif

namespace twinsim {

#if !TWINSIM_HAVE_MPI

bool MpiCompiled() { return false; }

namespace batch_internal {
BatchSummary RunBatchMpi(const Sweep&, const std::vector<SweepJob>&, const BatchOptions&) {
  throw std::logic_error("RunBatchMpi called in a build without MPI");
}
}  // namespace batch_internal

#else

bool MpiCompiled() { return true; }

namespace batch_internal {
namespace {

constexpr int kTagRequest = 1, kTagJob = 2, kTagResult = 3, kTagFinished = 4;

// Threads per rank: as asked, else this node's cores shared by its ranks.
int ThreadsPerRank(int requested) {
  if (requested > 0) return requested;
  const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
  const int ranks_here = local ? std::max(1, std::atoi(local)) : 1;
  return std::max(1, ResolveThreadCount(0) / ranks_here);
}

void SendText(const std::string& text, int tag) {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, 0, tag, MPI_COMM_WORLD);
}

// Rank 0: serve jobs and gather results until every rank has finished.
void Serve(int ranks, const std::function<std::optional<int>()>& next, const std::function<bool()>& local_running,
           const std::function<void(const std::string&)>& on_result) {
  int finished = 1;  // rank 0 itself: its workers are waited for separately
  // Polling backs off while idle (requests come once per job), so that this thread does
  // not take CPU from rank 0's own workers; a message resets it.
  int idle_us = 20;
  while (finished < ranks || local_running()) {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
    if (!flag) {
      std::this_thread::sleep_for(std::chrono::microseconds(idle_us));
      idle_us = std::min(2 * idle_us, 1000);
      continue;
    }
    idle_us = 20;
    int count = 0;
    MPI_Get_count(&status, MPI_CHAR, &count);
    std::string buffer(static_cast<std::size_t>(count), '\0');
    MPI_Recv(buffer.data(), count, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (status.MPI_TAG == kTagRequest) {
      const std::optional<int> job = next();
      const int reply = job ? *job : -1;
      MPI_Send(&reply, 1, MPI_INT, status.MPI_SOURCE, kTagJob, MPI_COMM_WORLD);
    } else if (status.MPI_TAG == kTagResult) {
      on_result(buffer);
    } else if (status.MPI_TAG == kTagFinished) {
      ++finished;
    }
  }
}

// Ranks but 0: `threads` workers whose requests and results the main thread forwards.
void Work(int threads, const std::function<std::string(int)>& run) {
  std::mutex mutex;
  std::condition_variable to_main, to_workers;
  int wanting = 0, alive = threads;
  bool stop = false;
  std::deque<int> assigned;
  std::deque<std::string> outbox;
  std::vector<std::thread> workers;
  for (int w = 0; w < threads; ++w) {
    workers.emplace_back([&] {
      for (;;) {
        int job = -1;
        {
          std::unique_lock<std::mutex> lock(mutex);
          ++wanting;
          to_main.notify_one();
          to_workers.wait(lock, [&] { return !assigned.empty() || stop; });
          if (assigned.empty()) {
            --wanting;
            --alive;
            to_main.notify_one();
            return;
          }
          job = assigned.front();
          assigned.pop_front();
        }
        std::string text = run(job);
        std::lock_guard<std::mutex> lock(mutex);
        outbox.push_back(std::move(text));
        to_main.notify_one();
      }
    });
  }
  for (;;) {
    std::unique_lock<std::mutex> lock(mutex);
    to_main.wait(lock, [&] { return !outbox.empty() || (wanting > 0 && !stop) || alive == 0; });
    if (!outbox.empty()) {
      const std::string text = std::move(outbox.front());
      outbox.pop_front();
      lock.unlock();
      SendText(text, kTagResult);
      continue;
    }
    if (alive == 0) break;
    lock.unlock();
    SendText("r", kTagRequest);
    int job = -1;
    MPI_Recv(&job, 1, MPI_INT, 0, kTagJob, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    lock.lock();
    if (job < 0) {
      stop = true;
      to_workers.notify_all();
    } else {
      assigned.push_back(job);
      --wanting;
      to_workers.notify_one();
    }
  }
  for (std::thread& t : workers) t.join();
  SendText("", kTagFinished);
}

// Rank 0 checks the folder and tells the other ranks whether to go on; a refusal finalises MPI and throws on every
// rank. Returns the jobs still to run (on rank 0; none elsewhere).
std::vector<int> PrepareOnRankZero(int rank, const Sweep& sweep, const std::vector<SweepJob>& jobs,
                                   const BatchOptions& options, std::vector<JobResult>* results, int* resumed) {
  std::vector<int> pending;
  std::string failure;
  if (rank == 0) {
    try {
      pending = PrepareFolder(sweep, jobs, options, results, resumed);
    } catch (const InputError& e) {
      failure = e.what();
    }
  }
  int ok = failure.empty() ? 1 : 0;
  MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!ok) {
    MPI_Finalize();
    if (rank == 0) throw InputError(failure);
    throw InputError("batch: rank 0 refused the sweep (see its message)");
  }
  return pending;
}

// Records a result another rank sent ("index\njson"), or says in `bad_message` that it does not parse.
void RecordRankResult(const std::string& message, const std::vector<SweepJob>& jobs, std::vector<JobResult>* results,
                      BatchReporter* reporter, std::string* bad_message) {
  const std::size_t newline = message.find('\n');
  const int index = newline == std::string::npos ? -1 : std::atoi(message.substr(0, newline).c_str());
  std::optional<JobResult> r;
  if (index >= 0 && index < static_cast<int>(jobs.size()))
    r = ParseJobResultJson(message.substr(newline + 1), jobs[index]);
  if (!r) {
    *bad_message = "a rank sent a result that does not parse: " + message.substr(0, 80);
    return;
  }
  (*results)[index] = *r;
  reporter->JobDone(r->status != "ok");
}

}  // namespace

BatchSummary RunBatchMpi(const Sweep& sweep, const std::vector<SweepJob>& jobs, const BatchOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  BatchSummary summary;
  summary.jobs = static_cast<int>(jobs.size());
  summary.ranks = ranks;
  summary.threads = ThreadsPerRank(options.jobs);
  summary.writer = rank == 0;

  // Rank 0 checks the folder first; the others learn whether to go on.
  std::vector<JobResult> results(jobs.size());
  const std::vector<int> pending = PrepareOnRankZero(rank, sweep, jobs, options, &results, &summary.resumed);

  if (rank != 0) {
    Work(summary.threads, [&](int index) {
      JobResult r;
      return std::to_string(index) + "\n" + RunJobIntoFolder(sweep, jobs[index], options, &r);
    });
    MPI_Finalize();
    return summary;
  }

  int failed_before = 0;
  for (const JobResult& r : results) failed_before += r.status == "failed";
  BatchReporter reporter(sweep, summary.jobs, summary.resumed, failed_before, options.progress);
  std::mutex mutex;
  std::size_t cursor = 0;
  const auto next = [&]() -> std::optional<int> {
    std::lock_guard<std::mutex> lock(mutex);
    if (cursor >= pending.size()) return std::nullopt;
    return pending[cursor++];
  };
  std::atomic<int> local_running{summary.threads};
  std::exception_ptr local_error;
  std::thread local([&] {
    try {
      RunLocalWorkers(summary.threads, next, [&](int index) {
        JobResult r;
        RunJobIntoFolder(sweep, jobs[index], options, &r);
        results[index] = r;
        reporter.JobDone(r.status != "ok");
      });
    } catch (...) {
      local_error = std::current_exception();
    }
    local_running = 0;
  });
  std::string bad_message;
  Serve(ranks, next, [&] { return local_running.load() > 0; }, [&](const std::string& message) {
    RecordRankResult(message, jobs, &results, &reporter, &bad_message);
  });
  local.join();
  reporter.Finish();
  MPI_Finalize();
  if (local_error) std::rethrow_exception(local_error);
  if (!bad_message.empty()) throw std::runtime_error(bad_message);
  summary.ran = static_cast<int>(pending.size());
  WriteSummary(sweep, jobs, results, options, &summary);
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace batch_internal

#endif

}  // namespace twinsim
