// Numeric derivatives at fixed steps in a fit's own coordinates, for the least squares
// (Ceres) of the arm's output error, the diagnosis and the omni identification. Ceres'
// numeric differentiation scales its step with |x| and takes sqrt(machine epsilon),
// 1.5e-8, where a coordinate is 0: a coupling or a drift starting at 0, on a cost that is
// jagged at fine scales (encoder counts, the controller's ticks), got derivatives of
// noise and the fit stalled at its start. Here each coordinate has its step, set once by
// the fit, and the columns may be evaluated on several threads (each on its own: the
// same numbers for any thread count).
//
//   problem.AddResidualBlock(new FixedStepCost(rows, steps, residual), nullptr, x.data());
#pragma once

#include <ceres/ceres.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace twinsim {

// The residual at coordinates x into out (rows values); false when it cannot be
// evaluated there. With threads > 1 it is called from several threads at once.
using FitResidualFunction = std::function<bool(const double* x, double* out)>;

// The Jacobian of `residual` at x by central differences, column k at steps[k], into
// jacobian (rows x steps.size(), row-major); the 2 steps.size() evaluations on `threads`
// threads (0: one per core). False when an evaluation fails.
inline bool CentralDifferences(const FitResidualFunction& residual, const double* x, const std::vector<double>& steps,
                               std::size_t rows, double* jacobian, int threads = 1) {
  const std::size_t n = steps.size();
  std::vector<std::vector<double>> sides(2 * n, std::vector<double>(rows));
  std::vector<char> ok(2 * n, 0);
  ParallelFor(static_cast<int>(2 * n), threads, [&](int c) {
    const auto k = static_cast<std::size_t>(c / 2);
    std::vector<double> at(x, x + n);
    at[k] += c % 2 == 0 ? steps[k] : -steps[k];
    ok[static_cast<std::size_t>(c)] = residual(at.data(), sides[static_cast<std::size_t>(c)].data());
  });
  for (char good : ok)
    if (!good) return false;
  for (std::size_t k = 0; k < n; ++k) {
    const std::vector<double>& plus = sides[2 * k];
    const std::vector<double>& minus = sides[2 * k + 1];
    for (std::size_t r = 0; r < rows; ++r) jacobian[r * n + k] = (plus[r] - minus[r]) / (2 * steps[k]);
  }
  return true;
}

// One parameter block of steps.size() coordinates, `rows` residuals.
class FixedStepCost : public ceres::CostFunction {
 public:
  FixedStepCost(std::size_t rows, std::vector<double> steps, FitResidualFunction residual, int threads = 1)
      : rows_(rows), steps_(std::move(steps)), residual_(std::move(residual)), threads_(threads) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(steps_.size()));
    set_num_residuals(static_cast<int>(rows_));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!residual_(parameters[0], residuals)) return false;
    if (!jacobians || !jacobians[0]) return true;
    return CentralDifferences(residual_, parameters[0], steps_, rows_, jacobians[0], threads_);
  }

 private:
  std::size_t rows_;
  std::vector<double> steps_;
  FitResidualFunction residual_;
  int threads_;
};

// Solves `problem` by `solver` with block x (its size lower.size()) kept within [lower,
// upper] (x clamped into it first); the iterations taken returned, the coordinates that
// ended within a thousandth of their range of a bound into *at_bound.
inline int SolveWithinBounds(ceres::Problem* problem, std::vector<double>* x, const std::vector<double>& lower,
                             const std::vector<double>& upper, const ceres::Solver::Options& solver,
                             std::vector<int>* at_bound) {
  const int p = static_cast<int>(lower.size());
  for (int k = 0; k < p; ++k) {
    (*x)[k] = std::clamp((*x)[k], lower[k], upper[k]);
    problem->SetParameterLowerBound(x->data(), k, lower[k]);
    problem->SetParameterUpperBound(x->data(), k, upper[k]);
  }
  ceres::Solver::Summary result;
  ceres::Solve(solver, problem, &result);
  at_bound->clear();
  for (int k = 0; k < p; ++k) {
    const double margin = 1e-3 * (upper[k] - lower[k]);
    if ((*x)[k] < lower[k] + margin || (*x)[k] > upper[k] - margin) at_bound->push_back(k);
  }
  return static_cast<int>(result.iterations.size()) - 1;
}

}  // namespace twinsim
