// Policy-gradient search over a parameter vector by simultaneous random perturbation
// (seed 000, section 3.4, equations 3 to 6; the method of Kohl and Stone).
//
// Each iteration draws n test sets around the current parameters p: every parameter
// of every set is moved by -eps_i, 0 or +eps_i with equal probability (eq. 3). All sets
// and the current set itself are scored by a caller-supplied batch evaluator (eq. 4:
// a higher quality is better). For each parameter i the sets fall into C+, C0 and C-
// by the sign of their perturbation of i, and each group's qualities are averaged
// with the exponent x of eq. 5 (a power mean of the qualities shifted to be positive;
// x = 1 is the plain mean, larger x listens more to the best sets). Eq. 6 then steps
//   p_i += 0                       if A0 > A+ and A0 > A-,
//   p_i += eta_i * sign(A+ - A-)   otherwise,
// and clamps p_i into [lower_i, upper_i]. Search stops after max_iterations, or
// earlier when the current set has not improved for `patience` iterations (an
// iteration where no parameter moves is no reason to stop: the next draws new sets).
//
//   PolicyGradientOptions o;  o.epsilon = ...;  o.eta = ...;
//   PolicyGradientSummary s = PolicyGradientSearch(p0, o, evaluate);
//   std::cout << s.BriefReport();
//
// The evaluator receives a whole iteration's sets at once, so it can score them in
// parallel (core/parallel.h); the search itself draws every perturbation from
// `seed` on the calling thread, so the same seed gives the same search.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace twinsim {

struct PolicyGradientOptions {
  int sets_per_iteration = 20;  // n, test sets drawn per iteration
  int max_iterations = 10;
  Eigen::VectorXd epsilon;      // per parameter, perturbation size (eq. 3), > 0
  Eigen::VectorXd eta;          // per parameter, step size (eq. 6), >= 0
  Eigen::VectorXd lower;        // per parameter, bounds for sets and steps (empty: none)
  Eigen::VectorXd upper;
  double exponent = 1;          // x of eq. 5, >= 1
  int patience = 0;             // stop after this many iterations without a better current set; 0: never
  std::uint64_t seed = 1;

  // False (and why) when sizes disagree or a value is out of range.
  bool IsValid(int num_parameters, std::string* why) const;
};

// One iteration: the current set, every test set and what they scored.
struct PolicyGradientIteration {
  int iteration = 0;                    // 0-based
  Eigen::VectorXd parameters;           // the current set at the start of the iteration
  double quality = 0;                   // the current set's own quality
  std::vector<Eigen::VectorXd> sets;    // n test sets
  std::vector<double> qualities;        // n, their qualities
  Eigen::VectorXi step;                 // per parameter: -1, 0 or +1 (times eta)
};

struct PolicyGradientSummary {
  std::vector<PolicyGradientIteration> iterations;
  Eigen::VectorXd final_parameters;  // after the last step (not yet scored)
  Eigen::VectorXd best_parameters;   // the best current set that was scored
  double best_quality = 0;
  int best_iteration = 0;
  int evaluations = 0;               // test runs, current sets included
  std::string termination;           // why the search stopped

  std::string BriefReport() const;
  std::string FullReport() const;
};

// Scores a batch of parameter sets; returns one quality per set, in order.
using BatchEvaluator = std::function<std::vector<double>(const std::vector<Eigen::VectorXd>&)>;
// Called after every iteration (e.g. for progress and logging).
using IterationCallback = std::function<void(const PolicyGradientIteration&)>;

// Runs the search from `initial`. Throws InputError when the options are
// not valid for initial.size() parameters, and passes on what the evaluator throws.
PolicyGradientSummary PolicyGradientSearch(const Eigen::VectorXd& initial, const PolicyGradientOptions& options,
                                           const BatchEvaluator& evaluate,
                                           const IterationCallback& on_iteration = {});

// The eq. 5 average of `values` (a subset of `all`): the power mean with exponent x of
// the values shifted by the smallest of `all` (plus a tiny margin so none is zero).
double PowerMeanQuality(const std::vector<double>& values, const std::vector<double>& all, double exponent);

// The eq. 6 step direction (-1, 0, +1) from the three group averages; a group that is
// empty (NaN average) does not vote.
int PolicyGradientStep(double a_plus, double a_zero, double a_minus);

}  // namespace twinsim
