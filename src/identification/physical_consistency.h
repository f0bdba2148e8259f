// From identified base parameters back to a full, physically consistent set of standard
// parameters (seed 001, section IV: the base parameters alone do not make a model).
//
// A link's inertial parameters belong to a real body exactly when its pseudo-inertia
//   J = [[Sigma, m c], [m c^T, m]],  Sigma = tr(I_o)/2 * 1 - I_o   (4 x 4, link origin)
// is positive definite (positive mass, inertia about the centre of mass positive
// definite and satisfying the triangle inequality). Each link is measured relative to
// the a-priori one, J' = J0^-1/2 J J0^-1/2 (the a-priori link is the identity), which
// makes all links and units alike, and these coordinates (with friction relative to the
// a-priori friction) are the metric for "close to the a-priori model".
//
// NearestStandardParameters() gives the standard parameters closest to the a-priori
// ones with K pi = beta (a minimum-norm correction in the null space of K).
// FitConsistentParameters() gives the physically consistent ones (every J' >= margin,
// friction >= 0) that best fit beta in the weighted-regressor metric ||R (K pi - beta)||,
// with a pull to the a-priori model for what the torques do not determine. The problem
// is convex (a least-squares objective over linear matrix inequalities) and is solved
// by a log-det barrier method with Newton steps: when some consistent parameters give
// beta exactly they are found (to within 1e-4 standard deviations); when none do (beta
// is no real arm's, e.g. negative friction), the weighted least-squares compromise.
//
//   Eigen::VectorXd pi = NearestStandardParameters(a_priori, base.from_standard, beta);
//   if (!WithStandardParameters(a_priori, pi).Validate().empty())
//     pi = FitConsistentParameters(a_priori, base.from_standard, r_w, beta).pi;
#pragma once

#include <Eigen/Core>

#include "robots/arm/arm_model.h"

namespace twinsim {

// Standard parameters (12 n) nearest to the a-priori model's with K pi = beta
// (K: r x 12 n with full row rank; beta: r).
Eigen::VectorXd NearestStandardParameters(const ArmModel& a_priori, const Eigen::MatrixXd& k,
                                          const Eigen::VectorXd& beta);

struct ConsistentFitOptions {
  double margin = 1e-6;     // each J' - margin * 1 stays positive definite (relative to the a-priori link)
  double pull = 1;          // weight of ||y - y0||^2 (y: the relative coordinates) against the barrier
  double tolerance = 1e-8;  // the data misfit's distance from optimal, in weighted units (standard deviations^2)
};

struct ConsistentFit {
  Eigen::VectorXd pi;    // 12 n standard parameters, physically consistent
  bool exact = false;    // ||R (K pi - beta)|| below 1e-3 per base parameter: beta itself is physical
  int iterations = 0;    // Newton steps
  bool converged = false;
};

// Physically consistent standard parameters that best fit beta in the metric of `r`
// (r x r upper triangular, the weighted regressor's R: ||R (K pi - beta)|| is the rise
// of the weighted torque residual). Throws InputError when the a-priori model itself is
// not physically consistent.
ConsistentFit FitConsistentParameters(const ArmModel& a_priori, const Eigen::MatrixXd& k, const Eigen::MatrixXd& r,
                                      const Eigen::VectorXd& beta, const ConsistentFitOptions& options = {});

}  // namespace twinsim
