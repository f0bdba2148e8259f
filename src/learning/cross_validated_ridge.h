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
#include <functional>
#include <optional>
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

// Which outputs keep their fit, judged by what the fits are used for rather than by their
// own errors: for every subset S of the outputs with a finite ridge (bit j: output j of y),
// the mean over folds of `cost(k, scale, weights)`, the weights (outputs x inputs, on
// inputs divided by `scale`) fitted on the other folds' rows of (x, y), each at its ridge,
// and zero outside S. `cost` returns nothing where fold k cannot be scored. Kept: the
// subset of least mean cost (on a tie, the one with fewer outputs). Fewer than two folds
// scored: every output kept, `folds` says how many were.
struct OutputSubsetChoice {
  int chosen = 0;  // the outputs with a finite ridge
  int kept = 0;
  int folds = 0;   // folds scored
  double cost_chosen = 0, cost_kept = 0, cost_none = 0;  // the mean costs
};
using FoldCost =
    std::function<std::optional<double>(int fold, const Eigen::VectorXd& scale, const Eigen::MatrixXd& weights)>;
OutputSubsetChoice ChooseOutputsByFoldCost(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                           const std::vector<int>& fold, const std::vector<double>& ridges,
                                           const FoldCost& cost);

}  // namespace twinsim
