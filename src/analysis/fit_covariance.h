// Standard errors of a Ceres least-squares fit whose residuals come in clusters that are
// correlated within and independent of each other: the output-error fits' windows and
// shooting segments (arm_output_error.h), whose simulated errors run smooth from row to
// row. The cluster-robust ("sandwich") covariance of clustered_standard_errors.h, from
// the problem's residuals and Jacobian; coordinates held at a bound are left out of A
// (fixed).
//
//   std::vector<double> se = ClusteredStandardErrors(&problem, blocks, residual_blocks, p, held, cluster_of);
#pragma once

#include <ceres/ceres.h>

#include <cstddef>
#include <vector>

namespace twinsim {

// The standard errors of the first `p` coordinates of `blocks` (parameter blocks of
// `problem`, the first holding at least p coordinates, in the order the Jacobian's
// columns take; the rest, like shooting segments' states, are nuisance coordinates whose
// uncertainty is propagated), at the blocks' current values. `held`: indices (< p) of
// coordinates at a bound, NaN and left out. `cluster_of`: each residual's cluster (0 to
// G - 1), the residuals in the order of `residual_blocks`. Evaluates the problem's residuals and Jacobian once on one thread (the cost
// functions' own threads as they have them). Empty when fewer than two clusters hold rows
// or the evaluation fails.
std::vector<double> ClusteredStandardErrors(ceres::Problem* problem, const std::vector<double*>& blocks,
                                            const std::vector<ceres::ResidualBlockId>& residual_blocks, int p,
                                            const std::vector<int>& held,
                                            const std::vector<int>& cluster_of);

}  // namespace twinsim
