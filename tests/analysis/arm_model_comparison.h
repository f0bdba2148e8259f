// How well models of an arm reproduce it: the comparison of the learned arm
// backend with the physical model on the writing task (docs/arm_learning.md).
//
// The same controller (computed torque over a nominal model `hat`, the writing task's
// reference) runs on the plant (the measurement) and on each candidate: the nominal
// physical model on a physics backend, or the learned backend. A candidate is judged by
// how far its closed-loop run lies from the measured one, per joint: the RMS and largest
// joint-position difference and the RMS difference of the torques the controller sent.
// Open loop, CompareOpenLoop() replays the measured drive torques on a candidate from
// measured states and reports its position error after a fixed time.
//
//   ArmReference ref = WritingTaskReference(hat, {});
//   TrackingTrial measured = RunTrackingTrial(plant, hat, ref, options);
//   ModelGap gap = CompareTrials("learned mlp", measured, RunTrackingTrial(hat, MakeLearnedArmBackend(hat, p), hat, ref, options));
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "backends/arm_backend_factory.h"
#include "control/computed_torque.h"
#include "learning/arm_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// One candidate against the measurement.
struct ModelGap {
  std::string name;
  bool finite = true;            // false when the candidate's run diverged (the numbers are then NaN)
  Eigen::VectorXd q_rms, q_max;  // dof, rad or m: candidate q - measured q over the run
  Eigen::VectorXd tau_rms;       // dof, N·m or N: RMS of the commands' difference
  // One line: name, worst joint's RMS and max position difference, torque difference.
  std::string BriefReport() const;
};

// The gap between a candidate's run and the measured one (same reference, same rows).
// Throws std::invalid_argument for runs of different shapes.
ModelGap CompareTrials(const std::string& name, const TrackingTrial& measured, const TrackingTrial& candidate);

// Builds a fresh backend for a candidate, for the model it was made for.
using ArmBackendFactory = std::function<std::unique_ptr<ArmBackend>()>;

struct ArmCandidate {
  std::string name;             // e.g. "physical (ode)", "learned (mlp)"
  ArmModel model;               // the model the loop runs with (its delay, sample time)
  ArmBackendFactory backend;
};

struct WritingComparison {
  TrackingTrial measured;           // the plant's run
  std::vector<TrackingTrial> runs;  // one per candidate (empty rows where it diverged)
  std::vector<ModelGap> gaps;       // one per candidate
  // A table: one row per candidate and joint.
  std::string FullReport() const;
};

// Runs `options` (computed torque over `hat`) along `reference` on the plant (on
// options.backend) and on every candidate, and compares. A candidate that runs away
// (CheckFailed) gets finite = false; other errors propagate.
WritingComparison CompareOnReference(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                                     const std::vector<ArmCandidate>& candidates, const TrackingOptions& options);

// Open loop, the physical model: the arm simulation of `model` on `backend` (its
// friction and effects included) started at row `start` of `log` from the measured
// state, with the commands logged before it in its delay line, and driven by the
// logged commands for `steps` samples; returns the q error (rad) at each step
// (steps x dof). Throws std::invalid_argument when the window does not fit the log,
// CheckFailed when the model runs away.
Eigen::MatrixXd PhysicalRolloutError(const ArmModel& model, const std::string& backend, const ArmLog& log, int start,
                                     int steps);

// Open-loop error statistics over held-out rows [first, last] of a log: free runs of
// `steps` samples started every `every` rows, for a learned predictor (ArmRolloutError)
// or the physical model (PhysicalRolloutError).
struct RolloutStats {
  Eigen::VectorXd one_step_rms;  // dof, rad: error after one sample
  Eigen::VectorXd final_rms;     // dof, rad: error after `steps` samples
  Eigen::VectorXd final_max;     // dof, rad
  int runs = 0;
};
RolloutStats PredictorRolloutStats(const ArmPredictor& predictor, const ArmLog& log, int first, int last, int steps,
                                   int every);
RolloutStats PhysicalRolloutStats(const ArmModel& model, const std::string& backend, const ArmLog& log, int first,
                                  int last, int steps, int every);

}  // namespace twinsim
