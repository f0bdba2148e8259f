// One job of a sweep (batch/sweep.h), run in-process into its own folder: the command
// the sweep names with the job's parameters, and the numbers it reports.
//
//   run      a scene (omni or arm) on its backend or the job's; writes what `twinsim
//            run` writes (plots when the sweep asks). Omni metrics: the first robot's
//            true final pose (final_x, final_y m, final_theta rad) and path_length (m);
//            arm: per joint rms_error_j, max_error_j (rad or m), saturated_j (share of
//            samples) and command_rms_j (N m or N).
//   replay   a log (given, or recorded by running the job's scene first into
//            trajectory.csv) through the job's model, as `twinsim replay`; writes
//            replay.csv. Omni: position_rmse (m), heading_rmse (rad) and predicted
//            (rows) at the horizon; arm: torque_error_rms_j and torque_relative_j.
//   compare  the log through every backend of `backends` (default: every physics
//            backend, plus learned with a predictor), as `twinsim compare`; writes
//            errors.csv. Metrics SOURCE_H_position_rmse (m) for H = 1f, 4f, 1s, free.
//
// A job that throws is a failed job: its error is kept, never rethrown.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "batch/sweep.h"

namespace twinsim {

struct JobResult {
  int index = 0;
  std::string id;
  std::string status;  // "ok" or "failed"
  std::string error;   // the failure's message on one line; empty when ok
  double wall_s = 0;   // s, wall time of the job (the one number that differs between runs)
  std::vector<std::pair<std::string, double>> metrics;  // in the command's order
};

// Loads the files `job` names with its parameters set, without running anything: a
// misspelt key or a parameter the files reject shows up before any job runs. Throws
// InputError naming the sweep file and what the files said.
void CheckSweepJobLoads(const Sweep& sweep, const SweepJob& job);

// Runs `job` of `sweep` and writes its files into `folder` (created; files written
// atomically). Never throws for a job's own failure: the result says "failed".
JobResult RunSweepJob(const Sweep& sweep, const SweepJob& job, const std::string& folder);

}  // namespace twinsim
