// The ridge of a ridge regression (predictor_file.h's FitRidge) chosen per output by
// cross-validation over folds, by the one-standard-error rule, with "no fit at all" (a
// zero prediction) among the candidates: what a residual predictor's correction needs,
// where zero means the physics alone (docs/learning.md, "The ridge, chosen per output").
//
//   std::vector<int> fold = ...;  // one per row of x: which fold it belongs to
//   std::vector<double> r = ChooseRidgesByOneStandardError(x, y, fold, {1e-3, 1e-2, 1e-1});
//   // r[j]: output j's ridge, or infinity where predicting zero is as good
#pragma once

#include <Eigen/Core>
#include <vector>

namespace twinsim {

// The mean squared error per output (columns of y) of a ridge fit predicting each fold of
// (x, y) from the others, one row per fold with a row to predict and at least 10 to fit
// on; an infinite ridge predicts zero.
Eigen::MatrixXd CrossValidatedErrors(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const std::vector<int>& fold,
                                     double ridge);

// Per output, the largest candidate whose mean fold error lies within one standard error
// (over the folds) of the best candidate's: `ridges` and infinity (a zero prediction,
// counting as the largest). Returns infinity for every output where no fold can be
// predicted.
std::vector<double> ChooseRidgesByOneStandardError(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                                   const std::vector<int>& fold, std::vector<double> ridges);

}  // namespace twinsim
