// A small multilayer perceptron for regression: the neural predictor of the learned
// simulator (seed 000, section 4).
//
// Fully connected tanh hidden layers and a linear output layer; inputs and outputs are
// normalised inside (per-column mean and standard deviation from the training set), so
// callers pass raw features. Training is full-batch or mini-batch Adam on the mean
// squared error with weight decay, seeded and single-threaded, so the same data and
// options give the same weights bit for bit; early stopping keeps the weights with the
// lowest error on a held-out validation split.
//
//   MlpOptions options;              // defaults suit ~10^4..10^5 samples of 42 inputs
//   MlpTrainSummary summary;
//   Mlp net = TrainMlp(x, y, options, &summary);   // x: N x in, y: N x out
//   Eigen::VectorXd out = net.Predict(x.row(0).transpose());
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace twinsim {

class Mlp {
 public:
  Mlp() = default;

  int num_inputs() const;
  int num_outputs() const;
  const std::vector<int>& hidden() const { return hidden_; }

  // Predicts one sample (raw, unnormalised input of num_inputs()).
  Eigen::VectorXd Predict(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  // Predicts many samples: N x in -> N x out.
  Eigen::MatrixXd PredictBatch(const Eigen::Ref<const Eigen::MatrixXd>& x) const;

  // Everything needed to rebuild the network, as plain numbers (for the predictor
  // file): layer sizes, normalisation, weights and biases.
  struct Parameters {
    std::vector<int> layer_sizes;          // in, hidden..., out
    Eigen::VectorXd input_mean, input_scale;    // in
    Eigen::VectorXd output_mean, output_scale;  // out
    std::vector<Eigen::MatrixXd> weights;  // layer l: sizes[l+1] x sizes[l]
    std::vector<Eigen::VectorXd> biases;   // layer l: sizes[l+1]
  };
  const Parameters& parameters() const { return p_; }
  // Rebuilds a network; throws InputError when the shapes disagree (the parameters
  // come from a predictor file).
  static Mlp FromParameters(Parameters p);

 private:
  Parameters p_;
  std::vector<int> hidden_;
};

struct MlpOptions {
  std::vector<int> hidden = {32, 32};  // hidden layer widths
  int max_epochs = 400;
  int batch_size = 256;                // 0 = full batch
  double learning_rate = 3e-3;         // Adam step size
  double weight_decay = 1e-5;          // L2 on weights (not biases)
  double validation_fraction = 0.2;    // the last fraction of rows (time order kept)
  int patience = 30;                   // epochs without validation improvement before stopping
  std::uint64_t seed = 1;              // initialisation and batch shuffling

  // True when usable; else says why in *why (every problem, separated by "; ").
  bool IsValid(std::string* why) const;
};

struct MlpTrainSummary {
  int epochs = 0;             // epochs run
  int best_epoch = 0;         // epoch whose weights were kept
  double train_mse = 0;       // normalised units, at best_epoch
  double validation_mse = 0;  // normalised units, at best_epoch (NaN without a validation split)
  bool stopped_early = false;
  std::string BriefReport() const;
};

// Trains on x (N x in) -> y (N x out); the validation split is the last rows. Throws
// InputError for invalid options, non-finite data, too few rows, or a training that
// diverged (lower the learning rate), std::invalid_argument for inconsistent shapes.
// `progress(epoch, max_epochs, validation_mse)` is called once per epoch (without a validation
// split it gets the epoch's mean training batch loss instead).
Mlp TrainMlp(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const MlpOptions& options,
             MlpTrainSummary* summary = nullptr,
             const std::function<void(int, int, double)>& progress = {});

// A predictor's network: trained on the rows of `train` (x, y) followed by the
// `held_out` rows it early-stops on (options' validation fraction set to their share).
// Returns the net and its one-line report in *report. Throws InputError "cannot train
// the neural net: ..." where TrainMlp throws it.
Mlp TrainMlpHoldingOut(const Eigen::MatrixXd& x_train, const Eigen::MatrixXd& y_train, const Eigen::MatrixXd& x_held,
                       const Eigen::MatrixXd& y_held, MlpOptions options,
                       const std::function<void(int, int, double)>& progress, std::string* report);

}  // namespace twinsim
