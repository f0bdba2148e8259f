// Standard errors of a least-squares fit whose residuals come in clusters that are
// correlated within and independent of each other (the output-error fits' windows and
// shooting segments, fit_covariance.h; the predictions ahead of an omni robot's drift,
// identification_omni/omni_drift_identification.h), so that the plain sigma^2 (J^T J)^-1
// would count every row as a measurement of its own and be far too small.
//
// At the solution x of min sum_i r_i(x)^2, with J = dr/dx and the clusters' scores
// g_c = J_c^T r_c (the rows of cluster c), the cluster-robust ("sandwich") covariance is
//
//   Cov(x) = G / (G - 1) A^+ (sum_c g_c g_c^T) A^+,   A = J^T J,
//
// G the number of clusters (Liang and Zeger 1986; Cameron and Miller 2015 for the small-
// sample factor). It needs no noise model: the scores' own spread from cluster to cluster
// says how far another run of the same clusters would move x. A direction A does not
// determine (an eigenvalue below 1e-10 of the largest, in A's own column scale) gives
// each coordinate with a share in it an infinite standard error.
//
//   std::vector<double> se = ClusteredStandardErrors(jacobian, residuals, held, cluster_of);
#pragma once

#include <Eigen/Core>

#include <vector>

namespace twinsim {

// The standard errors of A's coordinates (A = J^T J, q x q) from the clusters' scores
// (q x labels: column c is g_c, zero for a label without rows), G = `clusters` (2 or more).
Eigen::VectorXd ClusteredStandardErrors(const Eigen::MatrixXd& a, const Eigen::MatrixXd& scores, int clusters);

// The clusters that hold rows (G), and the labels' count (the largest label + 1) into
// *labels.
int ClustersWithRows(const std::vector<int>& cluster_of, int* labels);

// The same from a dense Jacobian (rows: the residuals r, columns: the coordinates).
// `held`: coordinates at a bound, NaN and left out of A. `cluster_of`: each row's cluster
// (0 to G - 1). Empty when fewer than two clusters hold rows or the sizes disagree.
std::vector<double> ClusteredStandardErrors(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r,
                                            const std::vector<int>& held, const std::vector<int>& cluster_of);

}  // namespace twinsim
