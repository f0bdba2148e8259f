// An ensemble of an omni scene: N rollouts that differ in the robots' driving noise (and
// a learned robot's drawn predictor) (`twinsim run SCENE --samples N`; docs/models.md,
// "Driving noise in the simulation").
//
// Sample k draws the slip from a stream of its own (Simulation::SetDrivingNoiseSample);
// the scene's seed, its commands, the camera's draws stay the same, so the spread of the
// samples' paths is what the robot's wander alone does to the scene (closed-loop
// behaviours react to it, as on the field). On the learned backend with a predictor that
// carries its own uncertainty (a linear one's weights, a network's ensemble), samples 1..
// also each draw it once (OmniEnsembleOptions::parameter_draws). Sample 0 is the plain run. Samples run in
// parallel; the result does not depend on the thread count.
//
//   OmniEnsemble e = RunOmniEnsemble(scene, "analytic", "", {100, 0});
//   WriteOmniRunFiles(scene, e.first, true, &files);  // sample 0, as `run` writes it
//   files.Write("samples.csv", FormatEnsembleCsv(e));
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "render/plot.h"
#include "scene/scene.h"
#include "sim/omni_simulation.h"

namespace twinsim {

struct OmniEnsembleOptions {
  int samples = 1;  // N >= 1
  int jobs = 0;     // threads; 0 = one per core
  // Samples 1.. also draw the backend's parameters from their own uncertainty, once for
  // the run (Simulation::DrawModelParameters: a linear predictor's weights or one of a
  // network's ensemble on the learned backend); sample 0 stays the plain run.
  bool parameter_draws = true;
};

struct OmniEnsemble {
  SimulationResult first;               // sample 0, the plain run
  std::vector<double> t;                // s, per frame
  // The first robot's true pose per sample and frame ([sample][frame]); a frame the
  // robot is off the field holds NaN.
  std::vector<std::vector<Pose2>> paths;
  // The first robot's true pose per frame with no robot drawing driving noise: the
  // deterministic run the fan spreads around.
  std::vector<Pose2> without_noise;
  std::string robot;                    // the first robot's name
};

// Throws InputError for N < 1, and when no robot of the scene draws driving noise (every
// sample would be the same run); else as RunOmniScene.
OmniEnsemble RunOmniEnsemble(const Scene& scene, const std::string& backend, const std::string& predictor,
                             const OmniEnsembleOptions& options, const std::function<void(int, int)>& progress = {});

// `t,sample,x,y,theta`: per frame N rows, sample 0..N-1, the first robot's true pose
// (frames it is off the field left out).
std::string FormatEnsembleCsv(const OmniEnsemble& ensemble);

// The fan of paths: every sample thin and grey, sample 0 in colour, and at every
// `mark_seconds` the ellipses that hold 50 % and 90 % of the samples (a Gaussian fitted
// to the samples' positions then). Equal scales on x and y.
SeriesPlot EnsemblePlot(const OmniEnsemble& ensemble, double mark_seconds = 1.0);

}  // namespace twinsim
