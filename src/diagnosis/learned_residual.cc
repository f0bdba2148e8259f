#include "diagnosis/learned_residual.h"

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {

RandomFeatureRidge RandomFeatureRidge::Fit(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, int features,
                                           std::uint64_t seed) {
  RandomFeatureRidge r;
  const Eigen::Index n = x.rows(), inputs = x.cols();
  r.mean_ = x.colwise().mean();
  r.scale_ = ((x.rowwise() - r.mean_).array().square().colwise().sum() / std::max<Eigen::Index>(n - 1, 1)).sqrt();
  for (Eigen::Index c = 0; c < inputs; ++c) {
    if (!(r.scale_[c] > 0)) r.scale_[c] = 1;  // a constant input
  }
  // Length scales 0.5, 1 and 2 (standardised units), a third of the features each: the
  // kernel's reach is not known in advance.
  Rng rng(seed);
  r.frequencies_.resize(inputs, features);
  r.phases_.resize(features);
  const double scales[3] = {0.5, 1.0, 2.0};
  for (int k = 0; k < features; ++k) {
    for (Eigen::Index c = 0; c < inputs; ++c) r.frequencies_(c, k) = rng.Gaussian() / scales[k % 3];
    r.phases_[k] = 2 * kPi * rng.Uniform();
  }
  const Eigen::MatrixXd phi = r.Features(x);
  const Eigen::Index width = phi.cols();
  auto solve = [&](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double lambda, double rows) {
    Eigen::MatrixXd normal = a;
    normal.diagonal().array() += lambda * rows;
    normal(0, 0) -= lambda * rows;  // the constant is not shrunk
    return Eigen::MatrixXd(normal.ldlt().solve(b));
  };
  // The penalty from a validation split: two tenths of the rows in time order (the
  // 4th and the 9th tenth), the rest trained on; the weights then from every row. No
  // correction at all (zero weights) competes too: a learner that only adds variance
  // must not be credited.
  std::vector<Eigen::Index> train, check;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index tenth = i * 10 / std::max<Eigen::Index>(n, 1);
    (tenth == 3 || tenth == 8 ? check : train).push_back(i);
  }
  Eigen::MatrixXd pt(static_cast<Eigen::Index>(train.size()), width), yt(static_cast<Eigen::Index>(train.size()), y.cols());
  Eigen::MatrixXd pc(static_cast<Eigen::Index>(check.size()), width), yc(static_cast<Eigen::Index>(check.size()), y.cols());
  for (std::size_t k = 0; k < train.size(); ++k) pt.row(static_cast<Eigen::Index>(k)) = phi.row(train[k]), yt.row(static_cast<Eigen::Index>(k)) = y.row(train[k]);
  for (std::size_t k = 0; k < check.size(); ++k) pc.row(static_cast<Eigen::Index>(k)) = phi.row(check[k]), yc.row(static_cast<Eigen::Index>(k)) = y.row(check[k]);
  const Eigen::MatrixXd at = pt.transpose() * pt, bt = pt.transpose() * yt;
  double best_error = yc.squaredNorm(), best_lambda = -1;
  for (double lambda : {1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0}) {
    const double error = (yc - pc * solve(at, bt, lambda, static_cast<double>(train.size()))).squaredNorm();
    if (error < best_error) best_error = error, best_lambda = lambda;
  }
  r.ridge_ = best_lambda;
  if (best_lambda < 0) {
    r.weights_ = Eigen::MatrixXd::Zero(width, y.cols());
    return r;
  }
  r.weights_ = solve(phi.transpose() * phi, phi.transpose() * y, best_lambda, static_cast<double>(n));
  return r;
}

Eigen::MatrixXd RandomFeatureRidge::Features(const Eigen::MatrixXd& x) const {
  const Eigen::Index n = x.rows(), inputs = x.cols(), features = frequencies_.cols();
  Eigen::MatrixXd z = (x.rowwise() - mean_).array().rowwise() / scale_.array();
  Eigen::MatrixXd phi(n, 1 + inputs + features);
  phi.col(0).setOnes();
  phi.middleCols(1, inputs) = z;
  phi.rightCols(features) = (std::sqrt(2.0) * ((z * frequencies_).rowwise() + phases_).array().cos()).matrix();
  return phi;
}

Eigen::MatrixXd RandomFeatureRidge::Predict(const Eigen::MatrixXd& x) const { return Features(x) * weights_; }

}  // namespace twinsim
