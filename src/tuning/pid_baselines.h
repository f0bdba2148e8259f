// Baselines for PID learning (seed 000, section 3; issue: "compare at equal numbers of
// test runs"): classic Ziegler-Nichols tuning and a general-purpose optimiser, scored by
// the same test run and quality as the policy-gradient search.
//
// Ziegler-Nichols (ultimate-gain method), per controller: the robot runs a velocity
// step on that axis alone with a P-only controller, filmed at the controller's rate;
// bisection on kp finds the ultimate gain Ku where the oscillation stops decaying,
// and its period Tu; then kp = 0.6 Ku, ki = 1.2 Ku / Tu, kd = 0.075 Ku Tu. The method
// says nothing of the integral and output limits and the slew rate: those keep their
// values from the start set (the hand-tuned ones when it is all zeros).
//
// The optimiser is NLopt's Subplex (a Nelder-Mead variant on subspaces, derivative free,
// bounded), maximising the same quality over the same parameters, in units of each
// parameter's scale, from the same start set.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "tuning/pid_tuning.h"

namespace twinsim {

struct BaselineResult {
  std::string method;
  int test_runs = 0;           // test runs (and step experiments) the method used
  Eigen::VectorXd parameters;  // 18
  TestRunScore score;          // its test run
  std::string detail;          // e.g. the ultimate gains found
};

struct UltimateGain {
  double ku = 0;      // N per m/s (N·m per rad/s for rotation), 0 when none was found
  double tu = 0;      // s, period of the sustained oscillation
  int experiments = 0;
};

// Finds the ultimate gain of controller `axis` (0 forward, 1 sideways, 2 rotation) of
// the evaluator's robot, from `parameters` (18; the other axes keep theirs), using at
// most `max_experiments` step experiments.
UltimateGain FindUltimateGain(const TestRunEvaluator& evaluator, const Eigen::VectorXd& parameters, int axis,
                              int max_experiments);

// Ziegler-Nichols tuning of the axes in `learn`, from `start` (18).
BaselineResult ZieglerNicholsBaseline(const TestRunEvaluator& evaluator, const Eigen::VectorXd& start,
                                      const std::array<bool, 3>& learn, int budget);

// NLopt Subplex on the parameters of the axes in `learn`, from `start`, within
// [0, upper x scale], with at most `budget` test runs.
BaselineResult OptimizerBaseline(const TestRunEvaluator& evaluator, const Eigen::VectorXd& start,
                                 const PidTuningOptions& options, int budget);

// The policy-gradient result, the start set, and both baselines at its number of test
// runs, in that order.
std::vector<BaselineResult> RunPidBaselines(const TestRunEvaluator& evaluator, const PidTuningResult& learned,
                                            const PidTuningOptions& options, bool quiet);

}  // namespace twinsim
