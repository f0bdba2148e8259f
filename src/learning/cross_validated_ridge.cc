#include "learning/cross_validated_ridge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "learning/predictor_file.h"

namespace twinsim {
namespace {

// The rows of fold f (*test) and of the others (*fit).
void SplitByFold(const std::vector<int>& fold, int f, std::vector<long>* fit, std::vector<long>* test) {
  for (std::size_t i = 0; i < fold.size(); ++i) (fold[i] == f ? test : fit)->push_back(static_cast<long>(i));
}

}  // namespace

Eigen::MatrixXd CrossValidatedErrors(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const std::vector<int>& fold,
                                     double ridge) {
  const int folds = fold.empty() ? 0 : *std::max_element(fold.begin(), fold.end()) + 1;
  std::vector<Eigen::VectorXd> rows;
  for (int f = 0; f < folds; ++f) {
    std::vector<long> fit_rows, test_rows;
    SplitByFold(fold, f, &fit_rows, &test_rows);
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

namespace {

// The mean cost of every subset of `chosen` for fold k (indexed by the subset's bits), or
// nothing where the fold cannot be scored.
std::optional<std::vector<double>> FoldCosts(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                             const std::vector<int>& fold, const std::vector<double>& ridges,
                                             int chosen, int k, const FoldCost& cost) {
  std::vector<long> rows, left_out;
  SplitByFold(fold, k, &rows, &left_out);
  if (rows.size() < 10) return std::nullopt;
  const Eigen::MatrixXd fx = x(rows, Eigen::all), fy = y(rows, Eigen::all);
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(y.cols(), x.cols());
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(x.cols());
  for (long j = 0; j < y.cols(); ++j)
    if (chosen >> j & 1) w.row(j) = FitRidge(fx, fy.col(j), ridges[static_cast<std::size_t>(j)], &scale).transpose();
  std::vector<double> out(std::size_t{1} << y.cols(), 0.0);
  for (int mask = 0; mask < static_cast<int>(out.size()); ++mask) {
    if (mask & ~chosen) continue;
    Eigen::MatrixXd wm = w;
    for (long j = 0; j < y.cols(); ++j)
      if (!(mask >> j & 1)) wm.row(j).setZero();
    const std::optional<double> c = cost(k, scale, wm);
    if (!c) return std::nullopt;
    out[static_cast<std::size_t>(mask)] = *c;
  }
  return out;
}

}  // namespace

OutputSubsetChoice ChooseOutputsByFoldCost(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                           const std::vector<int>& fold, const std::vector<double>& ridges,
                                           const FoldCost& cost) {
  OutputSubsetChoice c;
  for (long j = 0; j < y.cols(); ++j)
    if (std::isfinite(ridges[static_cast<std::size_t>(j)])) c.chosen |= 1 << j;
  c.kept = c.chosen;
  if (c.chosen == 0 || fold.empty()) return c;
  const int folds = *std::max_element(fold.begin(), fold.end()) + 1;
  std::vector<double> mean(std::size_t{1} << y.cols(), 0.0);
  for (int k = 0; k < folds; ++k) {
    const std::optional<std::vector<double>> f = FoldCosts(x, y, fold, ridges, c.chosen, k, cost);
    if (!f) continue;
    ++c.folds;
    for (std::size_t m = 0; m < mean.size(); ++m) mean[m] += (*f)[m];
  }
  if (c.folds < 2) return c;
  for (double& m : mean) m /= c.folds;
  auto bits = [](int mask) { return __builtin_popcount(static_cast<unsigned>(mask)); };
  for (int mask = 0; mask < static_cast<int>(mean.size()); ++mask) {
    if (mask & ~c.chosen) continue;
    const double a = mean[static_cast<std::size_t>(mask)], b = mean[static_cast<std::size_t>(c.kept)];
    if (a < b || (a == b && bits(mask) < bits(c.kept))) c.kept = mask;
  }
  c.cost_chosen = mean[static_cast<std::size_t>(c.chosen)];
  c.cost_kept = mean[static_cast<std::size_t>(c.kept)];
  c.cost_none = mean[0];
  return c;
}

}  // namespace twinsim
