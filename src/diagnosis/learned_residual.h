// The learned yardstick of the arm's diagnosis (docs/diagnose.md, "The learned
// yardstick"): a regression of the torque residual on the measured motion that knows no
// physics, in two stages. First an additive model (one piecewise-constant function of
// each input on 100 quantile bins) grown by componentwise boosting (Buehlmann and Yu,
// 2003): each step adds a share of the one input's function that explains most, so an
// effect of one joint stays on that joint's input. Then kernel ridge regression with a
// Gaussian kernel on what is left, approximated by random Fourier features (Rahimi and
// Recht, 2007) at three length scales, beside the inputs themselves (standardised on
// the training rows). The same data and seed give the same weights.
//
//   RandomFeatureRidge r = RandomFeatureRidge::Fit(x_fit, y_fit, 300, 1);
//   Eigen::MatrixXd correction = r.Predict(x_test);   // rows x outputs
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace twinsim {

class RandomFeatureRidge {
 public:
  // x: rows x inputs, y: rows x outputs, in time order. The boosting steps, the kernel
  // stage and its L2 penalty are chosen per output on a validation split of the rows
  // (the 4th and 9th tenths); where nothing beats predicting zero there, that output's
  // correction is zero.
  static RandomFeatureRidge Fit(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, int features, std::uint64_t seed);
  Eigen::MatrixXd Predict(const Eigen::MatrixXd& x) const;
  // The largest penalty chosen per training row (each output has its own); negative
  // when the kernel stage corrects no output.
  double ridge() const { return ridge_; }

 private:
  // Fit's steps: the inputs' mean and scale; the random features' frequencies and
  // phases; stage 1 (the additive model) on the rows, with what it leaves (*rest) and what
  // its fit on the training rows alone leaves (*rest_of_train); stage 2 (kernel ridge on
  // what stage 1 leaves, its penalty chosen on the check rows). Boost is stage 1's
  // boosting of output o on `rows` (bins: each row's bin per input): per step the error
  // left on `check` (none without check rows).
  void Standardise(const Eigen::MatrixXd& x);
  void DrawFeatures(Eigen::Index inputs, int features, std::uint64_t seed);
  void FitAdditive(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const std::vector<Eigen::Index>& train,
                   const std::vector<Eigen::Index>& check, Eigen::MatrixXd* rest, Eigen::MatrixXd* rest_of_train);
  std::vector<double> Boost(const Eigen::MatrixXi& bin, const Eigen::MatrixXd& y, Eigen::Index o,
                            const std::vector<Eigen::Index>& rows, const std::vector<Eigen::Index>& check, int steps);
  void FitKernel(const Eigen::MatrixXd& x, const Eigen::MatrixXd& rest, const Eigen::MatrixXd& rest_of_train,
                 const std::vector<Eigen::Index>& train, const std::vector<Eigen::Index>& check);
  Eigen::MatrixXd Features(const Eigen::MatrixXd& x) const;

  Eigen::MatrixXd Additive(const Eigen::MatrixXd& x) const;
  int Bin(Eigen::Index input, double v) const;

  Eigen::Index outputs_ = 0;
  Eigen::RowVectorXd mean_, scale_;  // inputs' standardisation
  std::vector<std::vector<double>> edges_;  // per input: the bins' inner edges (quantiles of the training rows)
  std::vector<Eigen::MatrixXd> bins_;  // per input: bins x outputs, the additive model's means
  Eigen::MatrixXd frequencies_;      // inputs x features
  Eigen::RowVectorXd phases_;        // features
  Eigen::MatrixXd weights_;          // (1 + inputs + features) x outputs
  double ridge_ = -1;
};

}  // namespace twinsim
