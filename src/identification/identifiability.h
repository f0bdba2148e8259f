// Practical identifiability of a least-squares fit: which parameters the data determine
// and which trade against each other (docs/identification.md, "Which parameters a log
// determines").
//
// From the fit's sensitivity matrix J (residuals by parameters, each column the
// derivative in the solver's coordinates), the columns normalised to unit length give
// S. Its smallest singular value s_min says how nearly some combination of parameters
// leaves every residual unchanged; the collinearity index gamma = 1 / s_min (Brun,
// Reichert and Kuensch 2001) is 1 for orthogonal sensitivities and grows without bound as
// parameters become interchangeable: gamma = 20 means a change of one parameter can be
// undone to 5 % by the others. While gamma is above the limit, the parameter with the
// largest share of the weakest direction (the right singular vector of s_min), weighed
// by the caller's preference, is held, and the others in that direction are its
// partners; a parameter the residuals do not depend on at all is held first.
//
//   Identifiability id = AnalyseIdentifiability(J, weights);
//   for (const HeldParameter& h : id.held) ...  // h.column trades with h.partners
#pragma once

#include <Eigen/Core>
#include <vector>

namespace twinsim {

struct HeldParameter {
  int column = 0;              // in J
  std::vector<int> partners;   // columns it trades with (empty: the residuals ignore it)
  double collinearity = 0;     // the index of the set it was held from (inf: ignored)
};

struct Identifiability {
  std::vector<int> kept;             // the columns determined together, in J's order
  std::vector<HeldParameter> held;   // in the order held
  double collinearity = 1;           // the index of the kept set
};

// `preference` (one per column, > 0; empty: all 1) scales each column's share of the
// weakest direction when choosing which to hold: a larger value is held sooner.
// `max_collinearity` > 1.
Identifiability AnalyseIdentifiability(const Eigen::MatrixXd& jacobian, const std::vector<double>& preference = {},
                                       double max_collinearity = 20);

// The inverse of J_k' J_k for the kept columns k (in `kept`'s order), the covariance of
// a unit-variance fit; empty when singular (reciprocal condition below 1e-12).
Eigen::MatrixXd KeptInverseNormal(const Eigen::MatrixXd& jacobian, const std::vector<int>& kept);

}  // namespace twinsim
