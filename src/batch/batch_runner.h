// Running a whole sweep (`twinsim batch`): every job into DIR/jobs/ID/, then
// DIR/summary.csv and DIR/summary.html.
//
// Jobs run on threads of this process (BatchOptions::jobs, 0: one per core). Started by
// mpirun in a build with MPI, the ranks share the sweep: rank 0 hands out jobs one at a
// time to whichever thread of whichever rank asks next (dynamic balancing) and gathers
// the results; every rank may run threads. Outputs do not depend on either: a job's
// seed comes from the sweep's seed and its number, and the summary is written in job
// order, so any thread and rank count gives the same bytes (but for wall times).
//
// A job's folder is complete when its result.json is there (written last) and names
// the same job and parameters; --resume keeps complete folders and runs the rest again
// from an empty folder, so an interrupted sweep ends as an uninterrupted one.
//
//   BatchOptions options;
//   options.out = "out/traction_grid";
//   BatchSummary s = RunBatch(LoadSweep("scenes/sweeps/traction_grid.yaml"), options);
//   std::puts(s.BriefReport().c_str());
#pragma once

#include <string>
#include <vector>

#include "batch/batch_job.h"
#include "batch/sweep.h"

namespace twinsim {

struct BatchOptions {
  std::string out;        // the sweep's folder
  int jobs = 0;           // threads per process; 0: the cores (under MPI: the cores per rank on the node)
  bool resume = false;    // keep complete job folders; without it `out` must hold no sweep
  bool progress = true;   // a live line on a terminal, plain lines otherwise (stderr)

  bool IsValid(std::string* why) const;
};

struct BatchSummary {
  int jobs = 0;           // in the sweep
  int ran = 0;            // run by this call (all ranks)
  int resumed = 0;        // complete from an earlier call
  int failed = 0;         // in the sweep (ran or resumed)
  int ranks = 1;          // MPI processes
  int threads = 1;        // per process
  double wall_s = 0;      // s
  bool writer = true;     // this process wrote the summary (false on MPI ranks but 0)
  std::vector<std::string> written;  // summary.csv, summary.html

  std::string BriefReport() const;
  std::string FullReport() const;
};

// Runs `sweep` as above. Throws InputError for invalid options or an `out` folder that
// holds another sweep (or any sweep, without resume) and when a file cannot be written.
// A job's own failure is not an error: it is a row with status "failed".
BatchSummary RunBatch(const Sweep& sweep, const BatchOptions& options);

// True when this process was started by an MPI launcher (mpirun, srun) with more than
// one rank, whether or not this build can use MPI.
bool StartedUnderMpi();
// True when this build was compiled with MPI.
bool MpiCompiled();

}  // namespace twinsim
