#include "learning/cross_validated_ridge.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "learning/predictor_file.h"

namespace twinsim {

Eigen::MatrixXd CrossValidatedErrors(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const std::vector<int>& fold,
                                     double ridge) {
  const int folds = fold.empty() ? 0 : *std::max_element(fold.begin(), fold.end()) + 1;
  std::vector<Eigen::VectorXd> rows;
  for (int f = 0; f < folds; ++f) {
    std::vector<int> fit_rows, test_rows;
    for (int i = 0; i < static_cast<int>(x.rows()); ++i)
      (fold[static_cast<std::size_t>(i)] == f ? test_rows : fit_rows).push_back(i);
    if (test_rows.empty() || fit_rows.size() < 10) continue;
    Eigen::MatrixXd predicted = Eigen::MatrixXd::Zero(static_cast<long>(test_rows.size()), y.cols());
    if (std::isfinite(ridge)) {
      Eigen::VectorXd scale;
      const Eigen::MatrixXd w = FitRidge(x(fit_rows, Eigen::all), y(fit_rows, Eigen::all), ridge, &scale);
      predicted = (x(test_rows, Eigen::all).array().rowwise() / scale.transpose().array()).matrix() * w;
    }
    rows.push_back((predicted - y(test_rows, Eigen::all)).colwise().squaredNorm().transpose() /
                   static_cast<double>(test_rows.size()));
  }
  Eigen::MatrixXd out(static_cast<long>(rows.size()), y.cols());
  for (std::size_t k = 0; k < rows.size(); ++k) out.row(static_cast<long>(k)) = rows[k].transpose();
  return out;
}

std::vector<double> ChooseRidgesByOneStandardError(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                                   const std::vector<int>& fold, std::vector<double> ridges) {
  std::sort(ridges.begin(), ridges.end());
  ridges.push_back(std::numeric_limits<double>::infinity());
  std::vector<Eigen::MatrixXd> errors;
  for (double r : ridges) errors.push_back(CrossValidatedErrors(x, y, fold, r));
  std::vector<double> chosen(static_cast<std::size_t>(y.cols()), ridges.back());
  if (errors.front().rows() == 0) return chosen;
  for (long j = 0; j < y.cols(); ++j) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < ridges.size(); ++k)
      if (errors[k].col(j).mean() < errors[best].col(j).mean()) best = k;
    const Eigen::VectorXd e = errors[best].col(j);
    const double n = static_cast<double>(e.size());
    const double se = e.size() > 1 ? std::sqrt((e.array() - e.mean()).square().sum() / (n - 1) / n) : 0.0;
    std::size_t keep = best;
    for (std::size_t k = best; k < ridges.size(); ++k)
      if (errors[k].col(j).mean() <= e.mean() + se) keep = k;  // ridges ascend
    chosen[static_cast<std::size_t>(j)] = ridges[keep];
  }
  return chosen;
}

}  // namespace twinsim
