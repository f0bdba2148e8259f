// Numeric derivatives at fixed steps in a fit's own coordinates, for the diagnosis's and
// the omni identification's least squares (Ceres). Ceres' numeric differentiation scales
// its step with |x| and takes sqrt(machine epsilon), 1.5e-8, where a coordinate is 0:
// a coupling or a drift starting at 0, on a cost that is jagged at fine scales (encoder
// counts, the controller's ticks), got derivatives of noise and the fit stalled at its
// start. Here each coordinate has its step, set once by the fit.
//
//   FixedStepCost cost(rows, steps, [&](const double* x, double* r) { return Residual(x, r); });
//   problem.AddResidualBlock(new FixedStepCost(...), nullptr, x.data());
#pragma once

#include <ceres/ceres.h>

#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

namespace twinsim {

// The residual at coordinates x into out (rows values); false when it cannot be
// evaluated there.
using FitResidualFunction = std::function<bool(const double* x, double* out)>;

// Column k of the Jacobian of `residual` at x by central differences at steps[k], into
// jacobian (rows x steps.size(), row-major). False when an evaluation fails.
inline bool CentralDifferences(const FitResidualFunction& residual, const double* x, const std::vector<double>& steps,
                               std::size_t rows, double* jacobian) {
  const std::size_t n = steps.size();
  std::vector<double> at(x, x + n), plus(rows), minus(rows);
  for (std::size_t k = 0; k < n; ++k) {
    const double x0 = at[k];
    at[k] = x0 + steps[k];
    if (!residual(at.data(), plus.data())) return false;
    at[k] = x0 - steps[k];
    if (!residual(at.data(), minus.data())) return false;
    at[k] = x0;
    for (std::size_t r = 0; r < rows; ++r) jacobian[r * n + k] = (plus[r] - minus[r]) / (2 * steps[k]);
  }
  return true;
}

// One parameter block of steps.size() coordinates, `rows` residuals.
class FixedStepCost : public ceres::CostFunction {
 public:
  FixedStepCost(std::size_t rows, std::vector<double> steps, FitResidualFunction residual)
      : rows_(rows), steps_(std::move(steps)), residual_(std::move(residual)) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(steps_.size()));
    set_num_residuals(static_cast<int>(rows_));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!residual_(parameters[0], residuals)) return false;
    if (!jacobians || !jacobians[0]) return true;
    return CentralDifferences(residual_, parameters[0], steps_, rows_, jacobians[0]);
  }

 private:
  std::size_t rows_;
  std::vector<double> steps_;
  FitResidualFunction residual_;
};

}  // namespace twinsim
