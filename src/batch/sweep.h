// A sweep: the jobs `twinsim batch` runs, read from YAML (docs/batch.md). A sweep names
// the command every job runs (run, replay or compare), parameters fixed for every job,
// a grid (every combination of the listed values, the first key slowest) and random
// draws (per grid point, seeded by the sweep's seed and the job's number):
//
//   name: traction_grid
//   seed: 1
//   command: compare
//   fixed: {scene: ../record_slipping_plant.yaml, model: ../../models/omni4.yaml}
//   grid:
//     plant.effects.traction_limit.a_max: [1.0, 1.5, 2.0, 2.5, 3.0]
//   random:
//     draws: 4
//     parameters:
//       plant.body.mass: {uniform: [2.2, 2.6]}
//
// Parameters are the job's inputs (scene, model, log, predictor, backend, backends,
// horizon, seed) and keys set in its files: `scene.KEY` in the scene, `plant.KEY` in the
// scene's robot models (the simulated plant), `model.KEY` in the model given to replay
// and compare (io/yaml_overrides.h). Paths are relative to the sweep file. `extends:`
// starts from another sweep file. Every problem is reported as "path:line:column: ...".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/error.h"

namespace twinsim {

// One value of a parameter: as YAML (what a job's files receive) and as text (what
// summary.csv shows).
struct SweepValue {
  YAML::Node node;
  std::string text;
};

// A parameter with its values: one (fixed), several (a grid axis), or a distribution.
struct SweepParameter {
  std::string name;
  SourceLocation where;            // in the sweep file
  std::vector<SweepValue> values;  // fixed: one; grid: the axis
  // Random draws: uniform, log_uniform or integer over [lo, hi], or a choice of values.
  std::string distribution;        // empty for fixed and grid parameters
  double lo = 0, hi = 0;
};

struct Sweep {
  std::string path;
  std::string name;
  std::uint64_t seed = 1;
  std::string command = "run";  // run | replay | compare
  bool plots = false;           // run: draw the scene's plots in every job folder
  std::vector<SweepParameter> fixed;
  std::vector<SweepParameter> grid;
  int draws = 0;                // random draws per grid point (0: no random part)
  std::vector<SweepParameter> random;

  // Grid points times draws (at least 1).
  std::int64_t num_jobs() const;
  // The names of the parameters that vary between jobs, in the file's order.
  std::vector<std::string> swept() const;
};

// One job of a sweep: its number, its folder name, its seed and every parameter's value.
struct SweepJob {
  int index = 0;
  std::string id;          // the folder name, the index zero-padded ("0007")
  std::uint64_t seed = 0;  // the `seed` parameter when swept or fixed, else drawn from the sweep's seed and index
  std::vector<std::pair<std::string, SweepValue>> parameters;  // fixed, grid, random, in the file's order

  // The value of `name`; nullptr when the job does not have it.
  const SweepValue* Find(const std::string& name) const;
};

// The most jobs one sweep may hold (a larger grid is refused when it is read).
inline constexpr std::int64_t kMaxSweepJobs = 1000000;

// Reads and checks a sweep file: unknown keys, parameter names, value types, paths that
// do not exist, a job count above kMaxSweepJobs. Throws InputError listing every problem.
Sweep LoadSweep(const std::string& path);

// Every job of the sweep, in order. Deterministic: the same sweep gives the same jobs.
std::vector<SweepJob> ExpandSweep(const Sweep& sweep);

}  // namespace twinsim
