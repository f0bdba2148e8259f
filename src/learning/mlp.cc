#include "learning/mlp.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/rng.h"

namespace twinsim {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

constexpr double kAdamBeta1 = 0.9;
constexpr double kAdamBeta2 = 0.999;
constexpr double kAdamEpsilon = 1e-8;
// Below this standard deviation a column is treated as constant (scale 1).
constexpr double kMinScale = 1e-12;
constexpr int kMinTrainingRows = 10;
// Rows per block when evaluating a whole split, to bound the activation memory.
constexpr Eigen::Index kEvalChunkRows = 4096;
// Rng::Derived streams, so initialisation and shuffling do not share draws.
constexpr std::uint64_t kInitStream = 0;
constexpr std::uint64_t kShuffleStream = 1;

std::string Join(const std::vector<std::string>& parts, const char* separator) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) out += separator;
    out += parts[i];
  }
  return out;
}

std::string SizesString(const std::vector<int>& sizes) {
  std::string out;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    if (i > 0) out += "-";
    out += std::to_string(sizes[i]);
  }
  return out;
}

std::string Number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", v);
  return buffer;
}

// Names the first non-finite entry of m, or returns "" when all are finite.
std::string FirstNonFinite(const Eigen::MatrixXd& m, const char* name) {
  if (m.allFinite()) return "";
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      if (!std::isfinite(m(r, c))) {
        return std::string(name) + " row " + std::to_string(r) + ", column " + std::to_string(c) +
               " (0-based) is " + Number(m(r, c));
      }
    }
  }
  return "";
}

// Per-column mean and scale (population standard deviation; 1 for constant columns so
// they pass through unscaled instead of being divided by ~0).
void ColumnStats(const Eigen::Ref<const Eigen::MatrixXd>& m, Eigen::VectorXd* mean,
                 Eigen::VectorXd* scale) {
  *mean = m.colwise().mean().transpose();
  const double n = static_cast<double>(m.rows());
  *scale = ((m.rowwise() - mean->transpose()).colwise().squaredNorm().transpose() / n).cwiseSqrt();
  for (Eigen::Index i = 0; i < scale->size(); ++i) {
    if (!((*scale)(i) >= kMinScale)) (*scale)(i) = 1.0;
  }
}

RowMatrix Normalise(const Eigen::Ref<const Eigen::MatrixXd>& m, const Eigen::VectorXd& mean,
                    const Eigen::VectorXd& scale) {
  return ((m.rowwise() - mean.transpose()).array().rowwise() / scale.transpose().array()).matrix();
}

// All weights and biases in one flat vector, so that Adam is a few vector operations.
// Layer l's weights (sizes[l+1] x sizes[l], column-major) start at weight_offset[l], its
// biases at bias_offset[l].
struct Layout {
  std::vector<int> sizes;
  std::vector<Eigen::Index> weight_offset, bias_offset;
  Eigen::Index total = 0;

  explicit Layout(std::vector<int> layer_sizes) : sizes(std::move(layer_sizes)) {
    for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
      weight_offset.push_back(total);
      total += static_cast<Eigen::Index>(sizes[l + 1]) * sizes[l];
      bias_offset.push_back(total);
      total += sizes[l + 1];
    }
  }
  int num_layers() const { return static_cast<int>(weight_offset.size()); }

  Eigen::Map<Eigen::MatrixXd> Weights(Eigen::VectorXd& flat, int l) const {
    return {flat.data() + weight_offset[l], sizes[l + 1], sizes[l]};
  }
  Eigen::Map<const Eigen::MatrixXd> Weights(const Eigen::VectorXd& flat, int l) const {
    return {flat.data() + weight_offset[l], sizes[l + 1], sizes[l]};
  }
  Eigen::Map<Eigen::VectorXd> Biases(Eigen::VectorXd& flat, int l) const {
    return {flat.data() + bias_offset[l], sizes[l + 1]};
  }
  Eigen::Map<const Eigen::VectorXd> Biases(const Eigen::VectorXd& flat, int l) const {
    return {flat.data() + bias_offset[l], sizes[l + 1]};
  }
};

// Forward pass over a batch. On entry acts[0] holds the normalised inputs (batch x in);
// on return acts[l] holds layer l's activations (batch x sizes[l]) and acts.back() the
// normalised outputs. Keeping every layer is what the backward pass needs.
void Forward(const Layout& layout, const Eigen::VectorXd& theta,
             std::vector<Eigen::MatrixXd>* acts) {
  const int n_layers = layout.num_layers();
  for (int l = 0; l < n_layers; ++l) {
    Eigen::MatrixXd& out = (*acts)[l + 1];
    out.noalias() = (*acts)[l] * layout.Weights(theta, l).transpose();
    out.rowwise() += layout.Biases(theta, l).transpose();
    if (l + 1 < n_layers) out = out.array().tanh().matrix();
  }
}

// Mean squared error (normalised units) of the network on all rows of x -> y, in
// blocks of rows so that large splits do not need large activation matrices.
double MeanSquaredError(const Layout& layout, const Eigen::VectorXd& theta, const RowMatrix& x,
                        const RowMatrix& y, std::vector<Eigen::MatrixXd>* acts) {
  double sum = 0;
  for (Eigen::Index start = 0; start < x.rows(); start += kEvalChunkRows) {
    const Eigen::Index rows = std::min(kEvalChunkRows, x.rows() - start);
    (*acts)[0] = x.middleRows(start, rows);
    Forward(layout, theta, acts);
    sum += (acts->back() - y.middleRows(start, rows)).squaredNorm();
  }
  return sum / (static_cast<double>(x.rows()) * static_cast<double>(y.cols()));
}

}  // namespace

int Mlp::num_inputs() const { return p_.layer_sizes.empty() ? 0 : p_.layer_sizes.front(); }
int Mlp::num_outputs() const { return p_.layer_sizes.empty() ? 0 : p_.layer_sizes.back(); }

Eigen::VectorXd Mlp::Predict(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  if (p_.weights.empty()) throw std::invalid_argument("Mlp::Predict: the network is empty");
  if (x.size() != num_inputs()) {
    throw std::invalid_argument("Mlp::Predict: input has " + std::to_string(x.size()) +
                                " values, the network takes " + std::to_string(num_inputs()));
  }
  // Per-thread scratch that only grows, so a call allocates nothing but its result
  // (Predict runs once per simulation step and must stay in the microseconds).
  thread_local Eigen::VectorXd scratch[2];
  const int widest = *std::max_element(p_.layer_sizes.begin(), p_.layer_sizes.end());
  for (Eigen::VectorXd& s : scratch) {
    if (s.size() < widest) s.resize(widest);
  }
  const int n_layers = static_cast<int>(p_.weights.size());
  scratch[0].head(x.size()) = (x - p_.input_mean).cwiseQuotient(p_.input_scale);
  for (int l = 0; l < n_layers; ++l) {
    const auto in = scratch[l % 2].head(p_.layer_sizes[l]);
    auto out = scratch[(l + 1) % 2].head(p_.layer_sizes[l + 1]);
    out.noalias() = p_.weights[l] * in;
    out += p_.biases[l];
    if (l + 1 < n_layers) out = out.array().tanh().matrix();
  }
  return scratch[n_layers % 2].head(num_outputs()).cwiseProduct(p_.output_scale) + p_.output_mean;
}

Eigen::MatrixXd Mlp::PredictBatch(const Eigen::Ref<const Eigen::MatrixXd>& x) const {
  if (p_.weights.empty()) throw std::invalid_argument("Mlp::PredictBatch: the network is empty");
  if (x.cols() != num_inputs()) {
    throw std::invalid_argument("Mlp::PredictBatch: input has " + std::to_string(x.cols()) +
                                " columns, the network takes " + std::to_string(num_inputs()));
  }
  const int n_layers = static_cast<int>(p_.weights.size());
  Eigen::MatrixXd a = ((x.rowwise() - p_.input_mean.transpose()).array().rowwise() /
                       p_.input_scale.transpose().array())
                          .matrix();
  Eigen::MatrixXd next;
  for (int l = 0; l < n_layers; ++l) {
    next.noalias() = a * p_.weights[l].transpose();
    next.rowwise() += p_.biases[l].transpose();
    if (l + 1 < n_layers) next = next.array().tanh().matrix();
    std::swap(a, next);
  }
  return ((a.array().rowwise() * p_.output_scale.transpose().array()).rowwise() +
          p_.output_mean.transpose().array())
      .matrix();
}

Mlp Mlp::FromParameters(Parameters p) {
  std::vector<std::string> problems;
  const std::vector<int>& sizes = p.layer_sizes;
  if (sizes.size() < 2) {
    throw InputError("Mlp::FromParameters: layer_sizes has " +
                     std::to_string(sizes.size()) +
                     " entries, need at least 2 (inputs and outputs)");
  }
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    if (sizes[i] < 1) {
      problems.push_back("layer_sizes[" + std::to_string(i) + "] is " + std::to_string(sizes[i]) +
                         " (must be >= 1)");
    }
  }
  if (!problems.empty())
    throw InputError("Mlp::FromParameters: " + Join(problems, "; "));

  const auto check_vector = [&problems](const Eigen::VectorXd& v, int expected,
                                        const std::string& name, bool positive) {
    if (v.size() != expected) {
      problems.push_back(name + " has " + std::to_string(v.size()) + " values, expected " +
                         std::to_string(expected));
    } else if (!v.allFinite()) {
      problems.push_back(name + " has non-finite values");
    } else if (positive && (v.array() <= 0).any()) {
      problems.push_back(name + " has values <= 0");
    }
  };
  check_vector(p.input_mean, sizes.front(), "input_mean", false);
  check_vector(p.input_scale, sizes.front(), "input_scale", true);
  check_vector(p.output_mean, sizes.back(), "output_mean", false);
  check_vector(p.output_scale, sizes.back(), "output_scale", true);

  const std::size_t n_layers = sizes.size() - 1;
  if (p.weights.size() != n_layers || p.biases.size() != n_layers) {
    problems.push_back("layer_sizes " + SizesString(sizes) + " needs " + std::to_string(n_layers) +
                       " weight matrices and bias vectors, got " +
                       std::to_string(p.weights.size()) + " and " +
                       std::to_string(p.biases.size()));
  } else {
    for (std::size_t l = 0; l < n_layers; ++l) {
      const std::string w = "weights[" + std::to_string(l) + "]";
      if (p.weights[l].rows() != sizes[l + 1] || p.weights[l].cols() != sizes[l]) {
        problems.push_back(w + " is " + std::to_string(p.weights[l].rows()) + " x " +
                           std::to_string(p.weights[l].cols()) + ", expected " +
                           std::to_string(sizes[l + 1]) + " x " + std::to_string(sizes[l]));
      } else if (!p.weights[l].allFinite()) {
        problems.push_back(w + " has non-finite values");
      }
      check_vector(p.biases[l], sizes[l + 1], "biases[" + std::to_string(l) + "]", false);
    }
  }
  if (!problems.empty())
    throw InputError("Mlp::FromParameters: " + Join(problems, "; "));

  Mlp net;
  net.hidden_.assign(sizes.begin() + 1, sizes.end() - 1);
  net.p_ = std::move(p);
  return net;
}

bool MlpOptions::IsValid(std::string* why) const {
  std::vector<std::string> problems;
  for (std::size_t i = 0; i < hidden.size(); ++i) {
    if (hidden[i] < 1 || hidden[i] > 4096) {
      problems.push_back("hidden[" + std::to_string(i) + "] is " + std::to_string(hidden[i]) +
                         " (must be 1 to 4096)");
    }
  }
  // At most a million: an ensemble's progress counts its members' epochs as one int.
  if (max_epochs < 1 || max_epochs > 1000000)
    problems.push_back("max_epochs is " + std::to_string(max_epochs) + " (must be 1 to 1000000)");
  if (batch_size < 0) {
    problems.push_back("batch_size is " + std::to_string(batch_size) +
                       " (must be >= 0; 0 = full batch)");
  }
  if (!(learning_rate > 0) || !std::isfinite(learning_rate)) {
    problems.push_back("learning_rate is " + Number(learning_rate) + " (must be > 0)");
  }
  if (!(weight_decay >= 0) || !std::isfinite(weight_decay)) {
    problems.push_back("weight_decay is " + Number(weight_decay) + " (must be >= 0)");
  }
  if (!(validation_fraction >= 0 && validation_fraction < 1)) {
    problems.push_back("validation_fraction is " + Number(validation_fraction) +
                       " (must be in [0, 1))");
  }
  if (patience < 1)
    problems.push_back("patience is " + std::to_string(patience) + " (must be >= 1)");
  if (why && !problems.empty()) *why = Join(problems, "; ");
  return problems.empty();
}

std::string MlpTrainSummary::BriefReport() const {
  std::string out = "mlp: " + std::to_string(epochs) + " epochs";
  if (std::isnan(validation_mse)) {
    out += " (kept the last, no validation split), train mse " + Number(train_mse);
  } else {
    out += " (best " + std::to_string(best_epoch) + (stopped_early ? ", stopped early" : "") +
           "), train mse " + Number(train_mse) + ", validation mse " + Number(validation_mse);
  }
  return out;
}

namespace {

// Throws for options, shapes or values TrainMlp cannot train on (as TrainMlp says).
void CheckTrainingData(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const MlpOptions& options) {
  if (std::string problems; !options.IsValid(&problems)) {
    throw InputError("TrainMlp: invalid options: " + problems);
  }
  if (x.rows() != y.rows()) {
    throw std::invalid_argument("TrainMlp: x has " + std::to_string(x.rows()) + " rows but y has " +
                                std::to_string(y.rows()));
  }
  if (x.cols() < 1 || y.cols() < 1) {
    throw std::invalid_argument("TrainMlp: x and y need at least one column (x is " +
                                std::to_string(x.rows()) + " x " + std::to_string(x.cols()) +
                                ", y is " + std::to_string(y.rows()) + " x " +
                                std::to_string(y.cols()) + ")");
  }
  for (const std::string& bad : {FirstNonFinite(x, "x"), FirstNonFinite(y, "y")}) {
    if (!bad.empty()) throw InputError("TrainMlp: " + bad);
  }

}

// Xavier/Glorot uniform weights keep tanh units out of saturation at the start; zero biases.
Eigen::VectorXd InitialParameters(const Layout& layout, std::uint64_t seed) {
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(layout.total);
  Rng rng = Rng::Derived(seed, kInitStream);
  for (int l = 0; l < layout.num_layers(); ++l) {
    const double limit = std::sqrt(6.0 / (layout.sizes[l] + layout.sizes[l + 1]));
    auto w = layout.Weights(theta, l);
    for (Eigen::Index c = 0; c < w.cols(); ++c) {
      for (Eigen::Index r = 0; r < w.rows(); ++r) w(r, c) = rng.Uniform(-limit, limit);
    }
  }
  return theta;
}

// Adam's running moments and its bias corrections' powers, and the passes' scratch.
struct Optimiser {
  Eigen::VectorXd grad, adam_m, adam_v;
  double beta1_power = 1, beta2_power = 1;
  Eigen::VectorXd decay_mask;         // 1 on weights, 0 on biases: weight decay applies to weights only
  std::vector<Eigen::MatrixXd> acts;  // per layer, the batch's activations
  Eigen::MatrixXd delta, delta_prev;  // batch x layer width: dLoss/dPreactivation
  Eigen::MatrixXd y_batch;            // batch x out
};

// One epoch of minibatch Adam over the training rows in `order`; returns the sum of
// squared errors over the epoch (normalised units).
double TrainEpoch(const Layout& layout, const RowMatrix& x_train, const RowMatrix& y_train, const std::vector<int>& order,
                  Eigen::Index batch_size, const MlpOptions& options, Eigen::VectorXd* theta_out, Optimiser* o) {
  Eigen::VectorXd& theta = *theta_out;
  std::vector<Eigen::MatrixXd>& acts = o->acts;
  Eigen::MatrixXd &delta = o->delta, &delta_prev = o->delta_prev, &y_batch = o->y_batch;
  Eigen::VectorXd &grad = o->grad, &adam_m = o->adam_m, &adam_v = o->adam_v;
  double &beta1_power = o->beta1_power, &beta2_power = o->beta2_power;
  const Eigen::VectorXd& decay_mask = o->decay_mask;
  const int n_layers = layout.num_layers();
  const Eigen::Index n_train = x_train.rows();
  const double n_out = static_cast<double>(y_train.cols());
  double loss_sum = 0;  // sum of squared errors over the epoch, normalised units
  for (Eigen::Index start = 0; start < n_train; start += batch_size) {
    const Eigen::Index rows = std::min(batch_size, n_train - start);
    acts[0].resize(rows, x_train.cols());
    y_batch.resize(rows, y_train.cols());
    for (Eigen::Index i = 0; i < rows; ++i) {
      acts[0].row(i) = x_train.row(order[start + i]);
      y_batch.row(i) = y_train.row(order[start + i]);
    }
    Forward(layout, theta, &acts);

    // Loss = mean over the batch's rows and outputs of the squared error.
    delta = acts.back() - y_batch;
    loss_sum += delta.squaredNorm();
    delta *= 2.0 / (static_cast<double>(rows) * n_out);
    for (int l = n_layers - 1; l >= 0; --l) {
      layout.Weights(grad, l).noalias() = delta.transpose() * acts[l];
      layout.Biases(grad, l) = delta.colwise().sum().transpose();
      if (l > 0) {
        delta_prev.noalias() = delta * layout.Weights(theta, l);
        delta_prev.array() *= 1.0 - acts[l].array().square();  // tanh' = 1 - tanh^2
        std::swap(delta, delta_prev);
      }
    }
    // L2 penalty (weight_decay / 2) |W|^2 added to the loss, i.e. coupled decay as in
    // classic Adam, not AdamW.
    grad += options.weight_decay * decay_mask.cwiseProduct(theta);

    beta1_power *= kAdamBeta1;
    beta2_power *= kAdamBeta2;
    adam_m = kAdamBeta1 * adam_m + (1 - kAdamBeta1) * grad;
    adam_v = kAdamBeta2 * adam_v + (1 - kAdamBeta2) * grad.cwiseAbs2();
    theta.array() -= options.learning_rate * (adam_m.array() / (1 - beta1_power)) /
                     ((adam_v.array() / (1 - beta2_power)).sqrt() + kAdamEpsilon);
  }
  return loss_sum;
}

// The training and the validation rows, each normalised by the training rows' statistics.
struct MlpSplit {
  Eigen::Index n_train = 0, n_val = 0;
  RowMatrix x_train, y_train, x_val, y_val;
};

// Holds out the last rows for validation and normalises both splits, keeping the statistics in `params`.
MlpSplit SplitAndNormalise(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const MlpOptions& options,
                           Mlp::Parameters* params) {
  // The validation rows are the last ones, so that with time-ordered data the network is
  // judged on a later stretch than it learned from. Any positive fraction keeps >= 1 row.
  MlpSplit split;
  const Eigen::Index n_rows = x.rows();
  Eigen::Index n_val = static_cast<Eigen::Index>(
      std::llround(static_cast<double>(n_rows) * options.validation_fraction));
  if (options.validation_fraction > 0 && n_val == 0) n_val = 1;
  const Eigen::Index n_train = n_rows - n_val;
  if (n_train < kMinTrainingRows) {
    throw InputError("TrainMlp: " + std::to_string(n_train) + " training rows (" +
                     std::to_string(n_rows) + " rows minus " + std::to_string(n_val) +
                     " for validation); need at least " +
                     std::to_string(kMinTrainingRows));
  }
  split.n_train = n_train;
  split.n_val = n_val;

  // Normalisation from the training rows only, so nothing of the validation split leaks in.
  ColumnStats(x.topRows(n_train), &params->input_mean, &params->input_scale);
  ColumnStats(y.topRows(n_train), &params->output_mean, &params->output_scale);
  split.x_train = Normalise(x.topRows(n_train), params->input_mean, params->input_scale);
  split.y_train = Normalise(y.topRows(n_train), params->output_mean, params->output_scale);
  split.x_val = Normalise(x.bottomRows(n_val), params->input_mean, params->input_scale);
  split.y_val = Normalise(y.bottomRows(n_val), params->output_mean, params->output_scale);
  return split;
}

// Adam's state at zero, with weight decay on the weights only and room for every layer's activations.
Optimiser StartOptimiser(const Layout& layout) {
  const int n_layers = layout.num_layers();
  Optimiser optimiser;
  optimiser.grad = optimiser.adam_m = optimiser.adam_v = Eigen::VectorXd::Zero(layout.total);
  optimiser.decay_mask = Eigen::VectorXd::Zero(layout.total);
  for (int l = 0; l < n_layers; ++l) layout.Weights(optimiser.decay_mask, l).setOnes();
  optimiser.acts.resize(static_cast<std::size_t>(n_layers) + 1);
  return optimiser;
}

// Where the early-stopping loop ended: its last epoch and the best validation epoch's parameters.
struct MlpStop {
  Eigen::VectorXd best_theta;
  double best_val = std::numeric_limits<double>::infinity();
  int best_epoch = 0;
  int epoch = 0;
  bool diverged = false;
};

// Trains epoch after epoch until max_epochs, a non-finite loss or `patience` epochs without a better validation loss.
MlpStop TrainUntilStopped(const Layout& layout, const MlpSplit& split, const MlpOptions& options,
                          const std::function<void(int, int, double)>& progress, Eigen::VectorXd* theta,
                          std::vector<Eigen::MatrixXd>* eval_acts) {
  const Eigen::Index n_train = split.n_train;
  Optimiser optimiser = StartOptimiser(layout);
  const Eigen::Index batch_size =
      options.batch_size == 0 ? n_train : std::min<Eigen::Index>(options.batch_size, n_train);
  const double n_out = static_cast<double>(split.y_train.cols());
  std::vector<int> order(n_train);
  std::iota(order.begin(), order.end(), 0);
  Rng shuffle_rng = Rng::Derived(options.seed, kShuffleStream);

  const bool has_validation = split.n_val > 0;
  MlpStop stop;
  while (stop.epoch < options.max_epochs) {
    ++stop.epoch;
    for (Eigen::Index i = n_train - 1; i > 0; --i) {
      std::swap(order[i], order[shuffle_rng.Index(static_cast<std::uint64_t>(i + 1))]);
    }
    const double loss_sum =
        TrainEpoch(layout, split.x_train, split.y_train, order, batch_size, options, theta, &optimiser);
    const double epoch_train_loss =
        loss_sum / (static_cast<double>(n_train) * n_out);  // mean over the epoch's batches' rows

    double reported = epoch_train_loss;
    if (has_validation) {
      const double val = MeanSquaredError(layout, *theta, split.x_val, split.y_val, eval_acts);
      reported = val;
      if (val < stop.best_val) {
        stop.best_val = val;
        stop.best_epoch = stop.epoch;
        stop.best_theta = *theta;
      }
    } else {
      stop.best_epoch = stop.epoch;
    }
    if (progress) progress(stop.epoch, options.max_epochs, reported);
    // A non-finite loss means the weights have blown up; later epochs cannot recover.
    if (!std::isfinite(reported)) {
      stop.diverged = true;
      break;
    }
    if (has_validation && stop.epoch - stop.best_epoch >= options.patience) break;
  }
  return stop;
}

}  // namespace

Mlp TrainMlp(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const MlpOptions& options,
             MlpTrainSummary* summary, const std::function<void(int, int, double)>& progress) {
  CheckTrainingData(x, y, options);
  Mlp::Parameters params;
  const MlpSplit split = SplitAndNormalise(x, y, options, &params);

  params.layer_sizes.push_back(static_cast<int>(x.cols()));
  params.layer_sizes.insert(params.layer_sizes.end(), options.hidden.begin(), options.hidden.end());
  params.layer_sizes.push_back(static_cast<int>(y.cols()));
  const Layout layout(params.layer_sizes);
  const int n_layers = layout.num_layers();

  Eigen::VectorXd theta = InitialParameters(layout, options.seed);
  std::vector<Eigen::MatrixXd> eval_acts(n_layers + 1);
  const MlpStop stop = TrainUntilStopped(layout, split, options, progress, &theta, &eval_acts);

  const bool has_validation = split.n_val > 0;
  const Eigen::VectorXd& kept = has_validation ? stop.best_theta : theta;
  if (kept.size() != layout.total || !kept.allFinite() || (stop.diverged && !has_validation)) {
    throw InputError("TrainMlp: training diverged (non-finite loss at epoch " +
                     std::to_string(stop.epoch) + "); lower learning_rate (now " +
                     Number(options.learning_rate) + ")");
  }
  for (int l = 0; l < n_layers; ++l) {
    params.weights.emplace_back(layout.Weights(kept, l));
    params.biases.emplace_back(layout.Biases(kept, l));
  }
  if (summary) {
    summary->epochs = stop.epoch;
    summary->best_epoch = stop.best_epoch;
    summary->train_mse = MeanSquaredError(layout, kept, split.x_train, split.y_train, &eval_acts);
    summary->validation_mse = has_validation ? stop.best_val : std::numeric_limits<double>::quiet_NaN();
    summary->stopped_early = stop.epoch < options.max_epochs;
  }
  return Mlp::FromParameters(std::move(params));
}

Mlp TrainMlpHoldingOut(const Eigen::MatrixXd& x_train, const Eigen::MatrixXd& y_train, const Eigen::MatrixXd& x_held,
                       const Eigen::MatrixXd& y_held, MlpOptions options,
                       const std::function<void(int, int, double)>& progress, std::string* report) {
  Eigen::MatrixXd x(x_train.rows() + x_held.rows(), x_train.cols());
  Eigen::MatrixXd y(x.rows(), y_train.cols());
  x << x_train, x_held;
  y << y_train, y_held;
  options.validation_fraction = static_cast<double>(x_held.rows()) / static_cast<double>(x.rows());
  MlpTrainSummary s;
  Mlp net;
  try {
    net = TrainMlp(x, y, options, &s, progress);
  } catch (const InputError& e) {
    throw InputError(std::string("cannot train the neural net: ") + e.what());
  }
  *report = s.BriefReport();
  return net;
}

}  // namespace twinsim
