#include "diagnosis/learned_residual.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {
namespace {

constexpr int kBins = 100;             // per input, of equal counts on the training rows
constexpr double kShrinkCount = 5;     // a bin's mean is sum / (count + this): sparse bins say little
constexpr int kBoostingSteps = 150;    // at most, per output
constexpr double kBoostingShare = 0.3; // of the chosen input's bin means added per step

}  // namespace

namespace {

// The validation split: two tenths of the rows in time order (the 4th and the 9th tenth).
void ValidationSplit(Eigen::Index n, std::vector<Eigen::Index>* train, std::vector<Eigen::Index>* check) {
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index tenth = i * 10 / std::max<Eigen::Index>(n, 1);
    (tenth == 3 || tenth == 8 ? check : train)->push_back(i);
  }
}

Eigen::MatrixXd RowsOf(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), m.cols());
  for (std::size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = m.row(rows[k]);
  return out;
}

// The ridge solution of (a + lambda rows I) w = b, the constant (feature 0) not shrunk.
Eigen::MatrixXd RidgeSolve(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double lambda, double rows) {
  Eigen::MatrixXd normal = a;
  normal.diagonal().array() += lambda * rows;
  normal(0, 0) -= lambda * rows;  // the constant is not shrunk
  return Eigen::MatrixXd(normal.ldlt().solve(b));
}

}  // namespace

RandomFeatureRidge RandomFeatureRidge::Fit(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, int features,
                                           std::uint64_t seed) {
  RandomFeatureRidge r;
  r.Standardise(x);
  r.DrawFeatures(x.cols(), features, seed);
  std::vector<Eigen::Index> train, check;
  ValidationSplit(x.rows(), &train, &check);
  Eigen::MatrixXd rest, rest_of_train;
  r.FitAdditive(x, y, train, check, &rest, &rest_of_train);
  r.FitKernel(x, rest, rest_of_train, train, check);
  return r;
}

void RandomFeatureRidge::Standardise(const Eigen::MatrixXd& x) {
  const Eigen::Index n = x.rows();
  mean_ = x.colwise().mean();
  scale_ = ((x.rowwise() - mean_).array().square().colwise().sum() / std::max<Eigen::Index>(n - 1, 1)).sqrt();
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    if (!(scale_[c] > 0)) scale_[c] = 1;  // a constant input
  }
}

void RandomFeatureRidge::DrawFeatures(Eigen::Index inputs, int features, std::uint64_t seed) {
  // Length scales 0.5, 1 and 2 (standardised units), a third of the features each: the
  // kernel's reach is not known in advance.
  Rng rng(seed);
  frequencies_.resize(inputs, features);
  phases_.resize(features);
  const double scales[3] = {0.5, 1.0, 2.0};
  for (int k = 0; k < features; ++k) {
    for (Eigen::Index c = 0; c < inputs; ++c) frequencies_(c, k) = rng.Gaussian() / scales[k % 3];
    phases_[k] = 2 * kPi * rng.Uniform();
  }
}

// Componentwise boosting, per output: each step fits every input's bin means to what is
// left and adds a share of the one input that explains most. Backfitting all inputs at
// once split one effect among inputs that move together (on a periodic trajectory every
// input is a function of the phase): the parts cancelled on the training rows and not
// off them (measured: a spring on joint 2, residual RMS 0.845 -> 0.825 on the test rows,
// where a straight line in q2 gives 0.350).
std::vector<double> RandomFeatureRidge::Boost(const Eigen::MatrixXi& bin, const Eigen::MatrixXd& y, Eigen::Index o,
                                              const std::vector<Eigen::Index>& rows,
                                              const std::vector<Eigen::Index>& check, int steps) {
  const Eigen::Index inputs = bin.cols();
  std::vector<double> left(rows.size()), check_left(check.size());
  for (std::size_t k = 0; k < rows.size(); ++k) left[k] = y(rows[k], o);
  for (std::size_t k = 0; k < check.size(); ++k) check_left[k] = y(check[k], o);
  std::vector<double> errors;
  std::vector<double> sum(kBins), count(kBins);
  for (int step = 0; step < steps; ++step) {
    Eigen::Index best = -1;
    double best_gain = 0;
    Eigen::VectorXd best_means;
    for (Eigen::Index c = 0; c < inputs; ++c) {
      std::fill(sum.begin(), sum.end(), 0.0);
      std::fill(count.begin(), count.end(), 0.0);
      for (std::size_t k = 0; k < rows.size(); ++k) {
        const int b = bin(rows[k], c);
        sum[static_cast<std::size_t>(b)] += left[k];
        count[static_cast<std::size_t>(b)] += 1;
      }
      // The squared error removed by subtracting the shrunk means m = s / (c + k0):
      // sum over bins of 2 m s - c m^2.
      Eigen::VectorXd means(kBins);
      double gain = 0;
      for (int b = 0; b < kBins; ++b) {
        const double m = sum[static_cast<std::size_t>(b)] / (count[static_cast<std::size_t>(b)] + kShrinkCount);
        means[b] = m;
        gain += 2 * m * sum[static_cast<std::size_t>(b)] - count[static_cast<std::size_t>(b)] * m * m;
      }
      if (gain > best_gain) best_gain = gain, best = c, best_means = means;
    }
    if (best < 0) break;
    best_means *= kBoostingShare;
    bins_[static_cast<std::size_t>(best)].col(o) += best_means;
    for (std::size_t k = 0; k < rows.size(); ++k) left[k] -= best_means[bin(rows[k], best)];
    if (!check.empty()) {
      double e = 0;
      for (std::size_t k = 0; k < check.size(); ++k) {
        check_left[k] -= best_means[bin(check[k], best)];
        e += check_left[k] * check_left[k];
      }
      errors.push_back(e);
    }
  }
  return errors;
}

void RandomFeatureRidge::FitAdditive(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                     const std::vector<Eigen::Index>& train, const std::vector<Eigen::Index>& check,
                                     Eigen::MatrixXd* rest, Eigen::MatrixXd* rest_of_train) {
  const Eigen::Index n = x.rows(), inputs = x.cols();
  // Stage 1: an additive model, one function of each input (piecewise constant on bins).
  outputs_ = y.cols();
  // Bins of equal counts: a bin fed by one rare event would learn that event's noise.
  edges_.assign(static_cast<std::size_t>(inputs), std::vector<double>());
  for (Eigen::Index c = 0; c < inputs; ++c) {
    std::vector<double> v(x.col(c).data(), x.col(c).data() + n);
    std::sort(v.begin(), v.end());
    for (int k = 1; k < kBins; ++k) edges_[static_cast<std::size_t>(c)].push_back(v[static_cast<std::size_t>(k) * v.size() / kBins]);
  }
  // Each row's bin in each input, once.
  Eigen::MatrixXi bin(n, inputs);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index c = 0; c < inputs; ++c) bin(i, c) = Bin(c, x(i, c));
  }
  // Each output keeps as many steps as lower its validation error most (none when no
  // step beats predicting zero), then is refitted with them on every row. The model of
  // the training rows alone is kept too: stage 2 chooses its penalty on what it leaves on
  // the check rows (what the refit on every row leaves there, it has partly fitted).
  bins_.assign(static_cast<std::size_t>(inputs), Eigen::MatrixXd::Zero(kBins, y.cols()));
  std::vector<Eigen::MatrixXd> train_bins = bins_;
  std::vector<Eigen::Index> all(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) all[static_cast<std::size_t>(i)] = i;
  for (Eigen::Index o = 0; o < outputs_; ++o) {
    double best_error = 0;
    for (Eigen::Index i : check) best_error += y(i, o) * y(i, o);
    const std::vector<double> errors = Boost(bin, y, o, train, check, kBoostingSteps);
    int steps = 0;
    for (std::size_t s = 0; s < errors.size(); ++s) {
      if (errors[s] < best_error) best_error = errors[s], steps = static_cast<int>(s) + 1;
    }
    for (auto& b : bins_) b.col(o).setZero();
    Boost(bin, y, o, train, {}, steps);
    for (std::size_t c = 0; c < train_bins.size(); ++c) train_bins[c].col(o) = bins_[c].col(o);
    for (auto& b : bins_) b.col(o).setZero();
    Boost(bin, y, o, all, {}, steps);
  }
  *rest = y - Additive(x);
  std::swap(bins_, train_bins);
  *rest_of_train = y - Additive(x);  // stage 1 fitted on the training rows only
  std::swap(bins_, train_bins);
}

void RandomFeatureRidge::FitKernel(const Eigen::MatrixXd& x, const Eigen::MatrixXd& rest,
                                   const Eigen::MatrixXd& rest_of_train, const std::vector<Eigen::Index>& train,
                                   const std::vector<Eigen::Index>& check) {
  // Stage 2: kernel ridge on what is left.
  const Eigen::MatrixXd phi = Features(x);
  const Eigen::Index width = phi.cols();
  // No correction at all (zero weights) competes too: a learner that only adds variance
  // must not be credited.
  const Eigen::MatrixXd pt = RowsOf(phi, train), pc = RowsOf(phi, check);
  const Eigen::MatrixXd rt = RowsOf(rest_of_train, train), rc = RowsOf(rest_of_train, check);
  const Eigen::MatrixXd at = pt.transpose() * pt, bt = pt.transpose() * rt;
  // The penalty per output; an output no penalty helps gets no correction.
  const Eigen::Index outputs = rest.cols();
  Eigen::RowVectorXd best_error = rc.colwise().squaredNorm();
  Eigen::RowVectorXd best_lambda = Eigen::RowVectorXd::Constant(outputs, -1);
  for (double lambda : {1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0}) {
    const Eigen::RowVectorXd error =
        (rc - pc * RidgeSolve(at, bt, lambda, static_cast<double>(train.size()))).colwise().squaredNorm();
    for (Eigen::Index o = 0; o < outputs; ++o) {
      if (error[o] < best_error[o]) best_error[o] = error[o], best_lambda[o] = lambda;
    }
  }
  weights_ = Eigen::MatrixXd::Zero(width, outputs);
  const Eigen::MatrixXd a_all = phi.transpose() * phi, b_all = phi.transpose() * rest;
  for (Eigen::Index o = 0; o < outputs; ++o) {
    if (best_lambda[o] > 0)
      weights_.col(o) = RidgeSolve(a_all, b_all.col(o), best_lambda[o], static_cast<double>(x.rows()));
  }
  ridge_ = best_lambda.maxCoeff();
}

int RandomFeatureRidge::Bin(Eigen::Index input, double v) const {
  const std::vector<double>& e = edges_[static_cast<std::size_t>(input)];
  return static_cast<int>(std::upper_bound(e.begin(), e.end(), v) - e.begin());
}

Eigen::MatrixXd RandomFeatureRidge::Additive(const Eigen::MatrixXd& x) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), outputs_);
  for (std::size_t c = 0; c < bins_.size(); ++c) {
    for (Eigen::Index i = 0; i < x.rows(); ++i) out.row(i) += bins_[c].row(Bin(static_cast<Eigen::Index>(c), x(i, static_cast<Eigen::Index>(c))));
  }
  return out;
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

Eigen::MatrixXd RandomFeatureRidge::Predict(const Eigen::MatrixXd& x) const {
  Eigen::MatrixXd out = Features(x) * weights_;
  if (!bins_.empty()) out += Additive(x);
  return out;
}

}  // namespace twinsim
