// Standard errors of a least-squares fit whose residuals come in clusters that are
// correlated within and independent of each other: the output-error fits' windows and
// shooting segments (arm_output_error.h), whose simulated errors run smooth from row to
// row, so that the plain sigma^2 (J^T J)^-1 would count every row as a measurement of
// its own and be far too small.
//
// At the solution x of min sum_i r_i(x)^2, with J = dr/dx and the clusters' scores
// g_c = J_c^T r_c (the rows of cluster c), the cluster-robust ("sandwich") covariance is
//
//   Cov(x) = G / (G - 1) A^+ (sum_c g_c g_c^T) A^+,   A = J^T J,
//
// G the number of clusters (Liang and Zeger 1986; Cameron and Miller 2015 for the small-
// sample factor). It needs no noise model: the scores' own spread from cluster to cluster
// says how far another run of the same clusters would move x. Coordinates held at a bound
// are left out of A (fixed); a direction A does not determine (an eigenvalue below 1e-10
// of the largest) gives each coordinate with a share in it an infinite standard error.
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
