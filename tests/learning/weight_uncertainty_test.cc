// A linear predictor's weights' own uncertainty (learning/predictor_file.h's
// RidgeWeightDirections, drawn by the learned backend once per sampled rollout;
// docs/learning.md, "The weights' own uncertainty").
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_replay.h"
#include "backends/learned/learned_omni_backend.h"
#include "core/error.h"
#include "core/rng.h"
#include "learning/learned_draws_util.h"
#include "learning/omni_predictor.h"
#include "learning/predictor_file.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A first-order autoregressive series: x_i = rho x_{i-1} + sqrt(1 - rho^2) w_i (unit variance).
Eigen::VectorXd Ar1(long n, double rho, Rng* rng) {
  Eigen::VectorXd x(n);
  double s = rng->Gaussian();
  for (long i = 0; i < n; ++i) {
    s = rho * s + std::sqrt(1 - rho * rho) * rng->Gaussian();
    x[i] = s;
  }
  return x;
}

// The covariance the directions stand for, in the inputs' own units (the directions are
// on the scaled inputs, like the weights): sum_l (D_l / scale)(D_l / scale)^T for output j.
Eigen::MatrixXd CovarianceOf(const RidgeWeightUncertainty& u, const Eigen::VectorXd& scale, int output) {
  const long in = scale.size();
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(in, in);
  for (const Eigen::MatrixXd& d : u.directions) {
    const Eigen::VectorXd v = d.row(output).transpose().cwiseQuotient(scale);
    c += v * v.transpose();
  }
  return c;
}

// Residuals and inputs that both wander (AR(1), rho 0.9, as a robot's speeds and its
// slip do from frame to frame) make the rows far from independent: the weights scatter
// from one data set to the next (1+rho^2)/(1-rho^2) = 9.5 times as much as the textbook
// sigma^2 (X^T X)^-1 says. The blocks' covariance (blocks of 100 rows, much longer than
// the correlation) finds the scatter measured over 300 data sets within 25 %; counting
// every row as its own block (the textbook's independence) is several times too small.
// A second output fixed at zero (an infinite ridge: a residual predictor's output
// without a correction) has no uncertainty.
TEST(RidgeWeightUncertainty, BlocksCountResidualsCorrelatedWithinThemOnce) {
  const long n = 3000, in = 2;
  const int sets = 300;
  Rng rng(5);
  std::vector<Eigen::VectorXd> fitted;  // output 0's weights, inputs' own units
  Eigen::MatrixXd blocks_cov = Eigen::MatrixXd::Zero(in, in), rows_cov = Eigen::MatrixXd::Zero(in, in);
  const std::vector<double> ridges{1e-9, std::numeric_limits<double>::infinity()};
  for (int s = 0; s < sets; ++s) {
    Eigen::MatrixXd x(n, in);
    x.col(0) = Ar1(n, 0.9, &rng);
    x.col(1) = 0.5 * Ar1(n, 0.9, &rng);
    Eigen::MatrixXd y(n, 2);
    y.col(0) = 0.7 * x.col(0) - 1.2 * x.col(1) + 0.3 * Ar1(n, 0.9, &rng);
    y.col(1) = 0.1 * Ar1(n, 0.0, &rng);
    Eigen::VectorXd scale;
    Eigen::MatrixXd w = FitRidge(x, y, ridges[0], &scale);
    w.col(1).setZero();  // fixed at zero, as an infinite ridge leaves it
    fitted.push_back(w.col(0).cwiseQuotient(scale));
    const RidgeWeightUncertainty by_blocks = RidgeWeightDirections(x, y, scale, w, ridges, 100, 1.0, 100);
    const RidgeWeightUncertainty by_rows = RidgeWeightDirections(x, y, scale, w, ridges, 1, 1.0, 100);
    ASSERT_EQ(by_blocks.blocks, 30);
    ASSERT_NEAR(by_blocks.share, 1.0, 1e-9);
    ASSERT_LE(by_blocks.directions.size(), static_cast<std::size_t>(in));  // one output uncertain: rank <= in
    for (const Eigen::MatrixXd& d : by_blocks.directions) ASSERT_EQ(d.row(1).norm(), 0.0);
    blocks_cov += CovarianceOf(by_blocks, scale, 0) / sets;
    rows_cov += CovarianceOf(by_rows, scale, 0) / sets;
  }
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(in);
  for (const Eigen::VectorXd& w : fitted) mean += w / sets;
  Eigen::MatrixXd measured = Eigen::MatrixXd::Zero(in, in);
  for (const Eigen::VectorXd& w : fitted) measured += (w - mean) * (w - mean).transpose() / (sets - 1);
  EXPECT_NEAR(mean[0], 0.7, 0.02);
  EXPECT_NEAR(mean[1], -1.2, 0.04);
  for (long k = 0; k < in; ++k) {
    EXPECT_NEAR(blocks_cov(k, k) / measured(k, k), 1.0, 0.25) << k;
    EXPECT_LT(rows_cov(k, k) / measured(k, k), 0.35) << k;
  }
}

// Too few rows for two blocks: nothing to say, no directions.
TEST(RidgeWeightUncertainty, OneBlockGivesNoDirections) {
  Rng rng(3);
  Eigen::MatrixXd x(50, 3), y(50, 1);
  for (long i = 0; i < 50; ++i) {
    for (long k = 0; k < 3; ++k) x(i, k) = rng.Gaussian();
    y(i, 0) = rng.Gaussian();
  }
  Eigen::VectorXd scale;
  const Eigen::MatrixXd w = FitRidge(x, y, 1e-3, &scale);
  const RidgeWeightUncertainty u = RidgeWeightDirections(x, y, scale, w, {1e-3}, 60, 0.95, 16);
  EXPECT_TRUE(u.directions.empty());
  EXPECT_EQ(u.blocks, 0);
}

class LearnedWeightDraws : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const OmniModel m = testing::Omni4();
    log_ = new OmniLog(testing::RecordLog(m, testing::RandomDrive(2.0, 2.0, 2.0), 40, 11, "analytic", "draws.csv"));
    predictor_ = new OmniPredictor(TrainOmniPredictor(m, {*log_}, OmniTrainOptions{}));
  }
  static void TearDownTestSuite() {
    delete log_;
    delete predictor_;
  }
  static OmniLog* log_;
  static OmniPredictor* predictor_;
};
OmniLog* LearnedWeightDraws::log_ = nullptr;
OmniPredictor* LearnedWeightDraws::predictor_ = nullptr;

// train's linear predictor carries its weights' uncertainty: directions over the
// training part's seconds, each the size of the weights it moves; the file keeps them to
// the bit; a predictor of more than a frame carries none, nor does a network (its output
// layer's uncertainty was measured and not kept, docs/learning.md).
TEST_F(LearnedWeightDraws, TrainingWritesTheDirectionsAndTheFileKeepsThem) {
  const RidgeWeightUncertainty& u = predictor_->weight_uncertainty();
  ASSERT_FALSE(u.directions.empty());
  EXPECT_LE(u.directions.size(), 16u);
  EXPECT_GE(u.share, 0.5);
  // 40 s, the last 20 % held out: 32 s of training windows in blocks of a second.
  EXPECT_NEAR(u.blocks, 32, 2);
  for (const Eigen::MatrixXd& d : u.directions) {
    EXPECT_EQ(d.rows(), 3);
    EXPECT_EQ(d.cols(), 42);
  }
  const std::string dir = testing::TempDir("weight_draws");
  predictor_->Save(dir + "/p.pred");
  const OmniPredictor q = OmniPredictor::Load(dir + "/p.pred");
  ASSERT_EQ(q.weight_uncertainty().directions.size(), u.directions.size());
  for (std::size_t l = 0; l < u.directions.size(); ++l) EXPECT_EQ(q.weight_uncertainty().directions[l], u.directions[l]);
  EXPECT_EQ(q.weight_uncertainty().blocks, u.blocks);
  EXPECT_EQ(q.weight_uncertainty().share, u.share);

  // A residual predictor's file with two directions (the fuzzer's seed) loads them.
  const OmniPredictor corpus =
      OmniPredictor::Load(testing::SourcePath("tests/fuzz/corpus/predictor/omni4_residual_weights.pred"));
  ASSERT_EQ(corpus.weight_uncertainty().directions.size(), 2u);
  EXPECT_EQ(corpus.weight_uncertainty().directions[1].cols(), 48);

  OmniTrainOptions four;
  four.horizon = 4;
  EXPECT_TRUE(TrainOmniPredictor(testing::Omni4(), {*log_}, four).weight_uncertainty().directions.empty());
  OmniTrainOptions network;
  network.kind = "mlp";
  network.mlp.max_epochs = 5;
  EXPECT_TRUE(TrainOmniPredictor(testing::Omni4(), {*log_}, network).weight_uncertainty().directions.empty());
}

// A drawn predictor's one-frame prediction scatters about the estimate's as the
// directions say (the covariance of d = sum_l z_l D_l x, over 4000 draws, within 10 % of
// sum_l (D_l x)(D_l x)^T on its diagonal), and the estimate's comes back exactly.
TEST_F(LearnedWeightDraws, DrawnWeightsScatterAsTheDirectionsSay) {
  const OmniPredictor& p = *predictor_;
  const RidgeWeightUncertainty& u = p.weight_uncertainty();
  ASSERT_FALSE(u.directions.empty());
  std::vector<double> x(42);
  for (int k = 0; k < 42; ++k) x[static_cast<std::size_t>(k)] = 0.02 * std::sin(0.7 * k);  // a moving robot's window
  const Eigen::Vector3d at = p.PredictDelta(x.data());
  // The inputs as the weights see them: the predictor's delta is linear in the weights,
  // so the directions' effect is their own prediction on a copy with those weights.
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  OmniPredictor moved = p;
  for (std::size_t l = 0; l < u.directions.size(); ++l) {
    Eigen::VectorXd z = Eigen::VectorXd::Zero(static_cast<long>(u.directions.size()));
    z[static_cast<long>(l)] = 1;
    moved.DrawWeights(p, z);
    const Eigen::Vector3d d = moved.PredictDelta(x.data()) - at;
    expected += d * d.transpose();
  }
  Rng rng(8);
  Eigen::Matrix3d measured = Eigen::Matrix3d::Zero();
  const int draws = 4000;
  for (int s = 0; s < draws; ++s) {
    Eigen::VectorXd z(static_cast<long>(u.directions.size()));
    for (long l = 0; l < z.size(); ++l) z[l] = rng.Gaussian();
    moved.DrawWeights(p, z);
    const Eigen::Vector3d d = moved.PredictDelta(x.data()) - at;
    measured += d * d.transpose() / draws;
  }
  for (int a = 0; a < 3; ++a) {
    ASSERT_GT(expected(a, a), 0) << a;
    EXPECT_NEAR(measured(a, a) / expected(a, a), 1.0, 0.1) << a;
  }
  moved.DrawWeights(p, Eigen::VectorXd::Zero(static_cast<long>(u.directions.size())));
  EXPECT_EQ(moved.PredictDelta(x.data()), at);
  EXPECT_THROW(moved.DrawWeights(p, Eigen::VectorXd::Zero(1 + static_cast<long>(u.directions.size()))),
               std::invalid_argument);
}

// The learned backend's sampled rollouts draw the weights once each: with the driving
// noise all but off, the samples still spread (by the weights alone), more at a second
// than a tenth of one since a weight's error carries on through every step; without the
// draws they all fall on the prediction. The prediction itself stays the estimate's,
// bit for bit.
TEST_F(LearnedWeightDraws, SampledRolloutsSpreadByTheWeightsAlone) {
  OmniReplayOptions o = testing::QuietLearnedReplay(*predictor_, 30, 16, 10);
  o.also = {3};
  OmniReplayResult drawn;
  const testing::DrawnSpread spread = testing::SpreadWithAndWithoutDraws(*log_, o, &drawn);
  double spread_short = 0;
  for (std::size_t i = 0; i < log_->rows.size(); ++i)
    if (drawn.also[0].predicted[i] && drawn.also[0].covariance.size() > i)
      spread_short += drawn.also[0].covariance[i].topLeftCorner<2, 2>().trace();
  ASSERT_GT(spread.rows, 50);
  EXPECT_EQ(spread.moved_predictions, 0);
  EXPECT_GT(spread.drawn, 1e-4);  // m: the weights' own spread a second ahead
  EXPECT_LT(spread.fixed, 1e-3 * spread.drawn);
  EXPECT_GT(spread.drawn * spread.drawn * spread.rows, 4 * spread_short);
}

// A file whose directions do not match the layout, or that gives them to a predictor of
// more than a frame or to a network, is refused with the file and the key.
TEST_F(LearnedWeightDraws, MalformedDirectionsAreInputErrors) {
  const std::string dir = testing::TempDir("weight_draws_bad");
  predictor_->Save(dir + "/p.pred");
  const std::string text = testing::ReadText(dir + "/p.pred");
  auto error_of = [&](const std::string& t) {
    const std::string path = testing::WriteText(dir + "/bad.pred", t);
    try {
      OmniPredictor::Load(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string wrong_count = text;
  const std::size_t at = wrong_count.find("count: ");
  ASSERT_NE(at, std::string::npos);
  wrong_count.replace(at, wrong_count.find('\n', at) - at, "count: 99");
  const std::string e = error_of(wrong_count);
  EXPECT_NE(e.find("bad.pred"), std::string::npos) << e;
  EXPECT_NE(e.find("'directions' in 'weight_uncertainty'"), std::string::npos) << e;
  // A predictor of four frames ahead drives no rollouts.
  std::string four = testing::ReadText(testing::SourcePath("tests/fuzz/corpus/predictor/omni4_h4.pred"));
  four += "weight_uncertainty: {blocks: 10, share: 0.9, count: 1, directions: [0]}\n";
  EXPECT_NE(error_of(four).find("only a linear predictor of one frame ahead"), std::string::npos) << error_of(four);
  std::string network = text;
  network.replace(network.find("kind: linear"), 12, "kind: mlp");
  EXPECT_NE(error_of(network).find("only a linear predictor of one frame ahead"), std::string::npos)
      << error_of(network);
}

}  // namespace
}  // namespace twinsim
