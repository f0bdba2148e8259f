#include "learning/mlp.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"

namespace twinsim {
namespace {

// y = [sin(x0) + 0.5 x1^2, x0 x1] on x uniform in [-2, 2]^2: smooth, and its second output
// has no linear part at all on this symmetric domain, so a linear fit cannot explain it.
void MakeNonlinearData(int rows, std::uint64_t seed, Eigen::MatrixXd* x, Eigen::MatrixXd* y) {
  Rng rng(seed);
  x->resize(rows, 2);
  y->resize(rows, 2);
  for (int i = 0; i < rows; ++i) {
    const double x0 = rng.Uniform(-2, 2), x1 = rng.Uniform(-2, 2);
    (*x)(i, 0) = x0;
    (*x)(i, 1) = x1;
    (*y)(i, 0) = std::sin(x0) + 0.5 * x1 * x1;
    (*y)(i, 1) = x0 * x1;
  }
}

// Per-column root mean square of m.
Eigen::ArrayXd ColumnRms(const Eigen::MatrixXd& m) {
  return m.array().square().colwise().mean().sqrt().transpose();
}

// Per-column standard deviation of m.
Eigen::ArrayXd ColumnStdDev(const Eigen::MatrixXd& m) {
  return ColumnRms(m.rowwise() - m.colwise().mean());
}

// Options for the small, quick fits of these tests (a few tenths of a second each).
MlpOptions QuickOptions() {
  MlpOptions options;
  options.hidden = {16, 16};
  options.max_epochs = 200;
  options.batch_size = 64;
  options.learning_rate = 1e-2;
  return options;
}

// The message of the E that f throws, or "" when it throws none (another exception
// escapes and fails the test).
template <class E, class F>
std::string ThrownMessage(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

bool SameParameters(const Mlp::Parameters& a, const Mlp::Parameters& b) {
  if (a.layer_sizes != b.layer_sizes || a.weights.size() != b.weights.size()) return false;
  for (std::size_t l = 0; l < a.weights.size(); ++l) {
    if (a.weights[l] != b.weights[l] || a.biases[l] != b.biases[l]) return false;
  }
  return a.input_mean == b.input_mean && a.input_scale == b.input_scale &&
         a.output_mean == b.output_mean && a.output_scale == b.output_scale;
}

TEST(Mlp, FitsNonlinearFunctionMuchBetterThanLinear) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(3000, 42, &x, &y);
  MlpTrainSummary summary;
  const Mlp net = TrainMlp(x, y, QuickOptions(), &summary);
  EXPECT_EQ(net.num_inputs(), 2);
  EXPECT_EQ(net.num_outputs(), 2);
  EXPECT_EQ(net.hidden(), (std::vector<int>{16, 16}));

  const int n_val = 600;  // the last 20%
  const int n_train = 3000 - n_val;
  const Eigen::MatrixXd x_val = x.bottomRows(n_val), y_val = y.bottomRows(n_val);
  const Eigen::ArrayXd rmse = ColumnRms(net.PredictBatch(x_val) - y_val);
  const Eigen::ArrayXd y_std = ColumnStdDev(y_val);  // ~0.94 and ~1.3

  // Least squares on [x, 1] over the same training rows.
  Eigen::MatrixXd design(3000, 3);
  design << x, Eigen::VectorXd::Ones(3000);
  const Eigen::MatrixXd coefficients =
      design.topRows(n_train).colPivHouseholderQr().solve(y.topRows(n_train));
  const Eigen::ArrayXd linear_rmse = ColumnRms(design.bottomRows(n_val) * coefficients - y_val);

  for (int k = 0; k < 2; ++k) {
    // The data are noise-free, so the error is all approximation error; these settings
    // reach ~1% of the output's spread, and 5% leaves room for other platforms' rounding.
    EXPECT_LT(rmse(k), 0.05 * y_std(k)) << "output " << k;
    // The linear fit leaves ~64% (output 0) and ~100% (output 1) of the spread.
    EXPECT_LT(rmse(k), 0.1 * linear_rmse(k)) << "output " << k;
  }
  // The summary's validation error is in normalised units (divided by the training std dev).
  EXPECT_LT(summary.validation_mse, 0.05 * 0.05);
  EXPECT_GT(summary.best_epoch, 0);
  EXPECT_LE(summary.best_epoch, summary.epochs);
}

TEST(Mlp, PredictMatchesPredictBatch) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(500, 3, &x, &y);
  MlpOptions options = QuickOptions();
  options.max_epochs = 5;
  const Mlp net = TrainMlp(x, y, options);
  const Eigen::MatrixXd batch = net.PredictBatch(x.topRows(20));
  for (int i = 0; i < 20; ++i) {
    const Eigen::VectorXd one = net.Predict(x.row(i).transpose());
    // Same arithmetic up to summation order inside the matrix products.
    EXPECT_LT((one - batch.row(i).transpose()).cwiseAbs().maxCoeff(), 1e-12) << "row " << i;
  }
  const std::string message =
      ThrownMessage<std::invalid_argument>([&] { net.Predict(Eigen::VectorXd::Zero(3)); });
  EXPECT_TRUE(Contains(message, "input has 3 values, the network takes 2")) << message;
  EXPECT_TRUE(Contains(ThrownMessage<std::invalid_argument>([] { Mlp().Predict(Eigen::VectorXd::Zero(2)); }),
                       "the network is empty"));
}

TEST(Mlp, TrainingIsDeterministicAndSeeded) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(600, 5, &x, &y);
  MlpOptions options = QuickOptions();
  options.max_epochs = 20;
  MlpTrainSummary s1, s2;
  const Mlp a = TrainMlp(x, y, options, &s1);
  const Mlp b = TrainMlp(x, y, options, &s2);
  EXPECT_TRUE(SameParameters(a.parameters(), b.parameters()));
  EXPECT_EQ(s1.validation_mse, s2.validation_mse);
  EXPECT_EQ(s1.best_epoch, s2.best_epoch);
  for (int i = 0; i < 10; ++i) {
    const Eigen::VectorXd pa = a.Predict(x.row(i).transpose()),
                          pb = b.Predict(x.row(i).transpose());
    EXPECT_EQ(pa(0), pb(0));  // bit for bit
    EXPECT_EQ(pa(1), pb(1));
  }

  options.seed = 2;
  const Mlp c = TrainMlp(x, y, options);
  EXPECT_NE(a.parameters().weights[0], c.parameters().weights[0]);
  EXPECT_NE(a.Predict(x.row(0).transpose()), c.Predict(x.row(0).transpose()));
}

TEST(Mlp, NormalisationMakesInputScaleAndOffsetIrrelevant) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(1000, 11, &x, &y);
  MlpOptions options = QuickOptions();
  options.max_epochs = 40;
  MlpTrainSummary plain, shifted;
  const Mlp net = TrainMlp(x, y, options, &plain);
  Eigen::MatrixXd x_shifted = x;
  x_shifted.col(0) = (1000 * x.col(0)).array() + 1e4;
  const Mlp net_shifted = TrainMlp(x_shifted, y, options, &shifted);

  // Normalisation undoes the affine map up to rounding (~1e-16 relative), which training
  // may amplify a little but not to the percent level.
  EXPECT_NEAR(shifted.validation_mse, plain.validation_mse, 0.01 * plain.validation_mse);
  EXPECT_LT(plain.validation_mse, 0.01);  // and it did learn something

  // Statistics come from the training rows (the first 800) only.
  const auto& p = net_shifted.parameters();
  EXPECT_NEAR(p.input_mean(0), x_shifted.col(0).head(800).mean(), 1e-9);
  EXPECT_NEAR(p.input_scale(0),
              std::sqrt((x_shifted.col(0).head(800).array() - p.input_mean(0)).square().mean()),
              1e-9);
  EXPECT_NEAR(p.output_mean(1), y.col(1).head(800).mean(), 1e-12);
}

TEST(Mlp, ConstantColumnsGetUnitScale) {
  Eigen::MatrixXd x2, y;
  MakeNonlinearData(300, 13, &x2, &y);
  Eigen::MatrixXd x(300, 3);
  x << x2, Eigen::VectorXd::Constant(300, 7.5);
  MlpOptions options = QuickOptions();
  options.max_epochs = 5;
  const Mlp net = TrainMlp(x, y, options);
  EXPECT_EQ(net.parameters().input_scale(2), 1.0);
  EXPECT_EQ(net.parameters().input_mean(2), 7.5);
  EXPECT_TRUE(net.PredictBatch(x).allFinite());
}

TEST(Mlp, EarlyStoppingKeepsTheBestEpoch) {
  // 80 rows where noise (std dev 1) swamps the signal: a wide network starts fitting the
  // noise within a few full-batch epochs (here validation error bottoms out at epoch 4),
  // so validation error turns up and training must stop long before max_epochs.
  Rng rng(17);
  Eigen::MatrixXd x(80, 3), y(80, 1);
  for (int i = 0; i < 80; ++i) {
    for (int j = 0; j < 3; ++j) x(i, j) = rng.Uniform(-1, 1);
    y(i, 0) = 0.3 * x(i, 0) + rng.Gaussian();
  }
  MlpOptions options;
  options.hidden = {64, 64};
  options.batch_size = 0;
  options.learning_rate = 3e-3;
  options.max_epochs = 2000;
  options.patience = 20;
  MlpTrainSummary summary;
  const Mlp net = TrainMlp(x, y, options, &summary);
  EXPECT_TRUE(summary.stopped_early);
  EXPECT_LT(summary.epochs, options.max_epochs);
  EXPECT_LT(summary.best_epoch, summary.epochs);
  EXPECT_EQ(summary.epochs, summary.best_epoch + options.patience);
  EXPECT_LT(summary.epochs, 200);
  EXPECT_LT(summary.train_mse, summary.validation_mse);  // it did overfit

  // Training again for exactly best_epoch epochs reproduces the kept weights bit for bit,
  // so they are that epoch's weights and not the last epoch's.
  options.max_epochs = summary.best_epoch;
  MlpTrainSummary again;
  const Mlp net_again = TrainMlp(x, y, options, &again);
  EXPECT_FALSE(again.stopped_early);
  EXPECT_EQ(again.best_epoch, summary.best_epoch);
  EXPECT_EQ(again.validation_mse, summary.validation_mse);
  EXPECT_TRUE(SameParameters(net.parameters(), net_again.parameters()));

  EXPECT_TRUE(Contains(summary.BriefReport(),
                       "epochs (best " + std::to_string(summary.best_epoch) + ", stopped early)"))
      << summary.BriefReport();
}

TEST(Mlp, WithoutValidationKeepsTheLastEpoch) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(200, 19, &x, &y);
  MlpOptions options = QuickOptions();
  options.max_epochs = 7;
  options.validation_fraction = 0;
  MlpTrainSummary summary;
  int calls = 0;
  TrainMlp(x, y, options, &summary, [&calls](int epoch, int max_epochs, double loss) {
    ++calls;
    EXPECT_EQ(epoch, calls);
    EXPECT_EQ(max_epochs, 7);
    EXPECT_TRUE(std::isfinite(loss));
  });
  EXPECT_EQ(calls, 7);
  EXPECT_EQ(summary.epochs, 7);
  EXPECT_EQ(summary.best_epoch, 7);
  EXPECT_FALSE(summary.stopped_early);
  EXPECT_TRUE(std::isnan(summary.validation_mse));
  EXPECT_GT(summary.train_mse, 0);
  EXPECT_TRUE(Contains(summary.BriefReport(), "no validation split")) << summary.BriefReport();
}

TEST(Mlp, BriefReportIsOneLine) {
  MlpTrainSummary summary;
  summary.epochs = 187;
  summary.best_epoch = 157;
  summary.train_mse = 0.0123;
  summary.validation_mse = 0.015;
  summary.stopped_early = true;
  EXPECT_EQ(summary.BriefReport(),
            "mlp: 187 epochs (best 157, stopped early), train mse 0.0123, validation mse 0.015");
}

TEST(Mlp, FromParametersRoundTripsAndChecksShapes) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(300, 23, &x, &y);
  MlpOptions options = QuickOptions();
  options.hidden = {8, 5};
  options.max_epochs = 5;
  const Mlp net = TrainMlp(x, y, options);
  const Mlp copy = Mlp::FromParameters(net.parameters());
  EXPECT_EQ(copy.hidden(), (std::vector<int>{8, 5}));
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(copy.Predict(x.row(i).transpose()), net.Predict(x.row(i).transpose()));  // exactly
  }

  const auto message_for = [&net](const std::function<void(Mlp::Parameters&)>& spoil) {
    Mlp::Parameters p = net.parameters();
    spoil(p);
    return ThrownMessage<InputError>([&p] { Mlp::FromParameters(p); });
  };
  struct Case {
    std::function<void(Mlp::Parameters&)> spoil;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {[](Mlp::Parameters& p) { p.weights[1].transposeInPlace(); },
       "weights[1] is 8 x 5, expected 5 x 8"},
      {[](Mlp::Parameters& p) { p.biases[2].resize(3); }, "biases[2] has 3 values, expected 2"},
      {[](Mlp::Parameters& p) { p.weights.pop_back(); },
       "needs 3 weight matrices and bias vectors, got 2 and 3"},
      {[](Mlp::Parameters& p) { p.input_mean.resize(4); }, "input_mean has 4 values, expected 2"},
      {[](Mlp::Parameters& p) { p.output_scale(0) = 0; }, "output_scale has values <= 0"},
      {[](Mlp::Parameters& p) { p.weights[0](1, 1) = std::numeric_limits<double>::quiet_NaN(); },
       "weights[0] has non-finite values"},
      {[](Mlp::Parameters& p) { p.layer_sizes = {2}; }, "need at least 2"},
      {[](Mlp::Parameters& p) { p.layer_sizes[1] = 0; }, "layer_sizes[1] is 0"},
  };
  for (const Case& c : cases) {
    const std::string message = message_for(c.spoil);
    EXPECT_TRUE(Contains(message, "Mlp::FromParameters: ")) << message;
    EXPECT_TRUE(Contains(message, c.expected)) << "expected '" << c.expected << "' in: " << message;
  }
}

TEST(Mlp, InvalidOptionsThrow) {
  std::string why;
  EXPECT_TRUE(MlpOptions().IsValid(&why));
  EXPECT_EQ(why, "");
  Eigen::MatrixXd x, y;
  MakeNonlinearData(100, 29, &x, &y);
  struct Case {
    std::function<void(MlpOptions&)> spoil;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {[](MlpOptions& o) {
         o.hidden = {16, 0};
       },
       "hidden[1] is 0 (must be 1 to 4096)"},
      {[](MlpOptions& o) { o.max_epochs = 0; }, "max_epochs is 0 (must be 1 to 1000000)"},
      {[](MlpOptions& o) { o.max_epochs = 1000001; }, "max_epochs is 1000001 (must be 1 to 1000000)"},
      {[](MlpOptions& o) { o.batch_size = -1; }, "batch_size is -1 (must be >= 0"},
      {[](MlpOptions& o) { o.learning_rate = 0; }, "learning_rate is 0 (must be > 0)"},
      {[](MlpOptions& o) { o.learning_rate = std::nan(""); }, "learning_rate is nan"},
      {[](MlpOptions& o) { o.weight_decay = -1e-3; }, "weight_decay is -0.001 (must be >= 0)"},
      {[](MlpOptions& o) { o.validation_fraction = 1; },
       "validation_fraction is 1 (must be in [0, 1))"},
      {[](MlpOptions& o) { o.validation_fraction = -0.1; }, "validation_fraction is -0.1"},
      {[](MlpOptions& o) { o.patience = 0; }, "patience is 0 (must be >= 1)"},
  };
  for (const Case& c : cases) {
    MlpOptions options;
    c.spoil(options);
    std::string problems;
    EXPECT_FALSE(options.IsValid(&problems));
    EXPECT_TRUE(Contains(problems, c.expected)) << problems;
    const std::string message = ThrownMessage<InputError>([&] { TrainMlp(x, y, options); });
    EXPECT_TRUE(Contains(message, "TrainMlp: invalid options: " + c.expected)) << message;
  }
  // Every problem is named at once.
  MlpOptions two;
  two.max_epochs = 0;
  two.patience = 0;
  EXPECT_FALSE(two.IsValid(&why));
  EXPECT_EQ(why, "max_epochs is 0 (must be 1 to 1000000); patience is 0 (must be >= 1)");
}

TEST(Mlp, BadDataThrows) {
  Eigen::MatrixXd x, y;
  MakeNonlinearData(100, 31, &x, &y);
  const MlpOptions options = QuickOptions();
  const auto message_for = [&options](const Eigen::MatrixXd& xs, const Eigen::MatrixXd& ys) {
    return ThrownMessage<InputError>([&] { TrainMlp(xs, ys, options); });
  };

  Eigen::MatrixXd bad = x;
  bad(7, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message_for(bad, y), "TrainMlp: x row 7, column 1 (0-based) is nan");
  bad = y;
  bad(3, 0) = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(message_for(x, bad), "TrainMlp: y row 3, column 0 (0-based) is -inf");
  // Shapes that disagree are the caller's bug, not the data's.
  EXPECT_EQ(ThrownMessage<std::invalid_argument>([&] { TrainMlp(x, y.topRows(99), options); }),
            "TrainMlp: x has 100 rows but y has 99");
  // 11 rows leave 9 for training once round(0.2 * 11) = 2 go to validation.
  EXPECT_EQ(message_for(x.topRows(11), y.topRows(11)),
            "TrainMlp: 9 training rows (11 rows minus 2 for validation); need at least 10");
  EXPECT_EQ(message_for(x.topRows(12), y.topRows(12)), "");  // 10 training rows are enough
}

}  // namespace
}  // namespace twinsim
