// A network's ensemble (`train --kind mlp --members N`): its further members trained on
// block bootstraps of the training windows, drawn one per sampled rollout by the learned
// backend (docs/learning.md, "An ensemble of networks").
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_replay.h"
#include "core/error.h"
#include "learning/learned_draws_util.h"
#include "learning/omni_predictor.h"
#include "test_util.h"

namespace twinsim {
namespace {

class NetworkEnsemble : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const OmniModel m = testing::Omni4();
    log_ = new OmniLog(testing::RecordLog(m, testing::RandomDrive(2.0, 2.0, 2.0), 30, 12, "analytic", "ensemble.csv"));
    OmniTrainOptions o;
    o.kind = "mlp";
    o.mlp.hidden = {16};
    o.mlp.max_epochs = 40;
    alone_ = new OmniPredictor(TrainOmniPredictor(m, {*log_}, o));
    o.members = 3;
    ensemble_ = new OmniPredictor(TrainOmniPredictor(m, {*log_}, o));
  }
  static void TearDownTestSuite() {
    delete log_;
    delete alone_;
    delete ensemble_;
  }
  // A moving robot's window of inputs.
  static std::vector<double> Window(double amplitude) {
    std::vector<double> x(42);
    for (int k = 0; k < 42; ++k) x[static_cast<std::size_t>(k)] = amplitude * std::sin(0.7 * k);
    return x;
  }
  static OmniLog* log_;
  static OmniPredictor* alone_;
  static OmniPredictor* ensemble_;
};
OmniLog* NetworkEnsemble::log_ = nullptr;
OmniPredictor* NetworkEnsemble::alone_ = nullptr;
OmniPredictor* NetworkEnsemble::ensemble_ = nullptr;

// Member 0 is the network trained alone, to the bit, so the prediction does not change;
// the others, each from its own start on its own bootstrap, predict otherwise; the file
// keeps every member to the bit.
TEST_F(NetworkEnsemble, TheFirstMemberIsTheNetworkAloneAndTheFileKeepsThemAll) {
  ASSERT_EQ(ensemble_->ensemble().size(), 2u);
  EXPECT_TRUE(alone_->ensemble().empty());
  const std::vector<double> x = Window(0.02);
  const Eigen::Vector3d at = ensemble_->PredictDelta(x.data());
  EXPECT_EQ(at, alone_->PredictDelta(x.data()));
  OmniPredictor drawn = *ensemble_;
  std::vector<Eigen::Vector3d> members;
  for (int k = 0; k < 3; ++k) {
    drawn.DrawMember(*ensemble_, k);
    members.push_back(drawn.PredictDelta(x.data()));
  }
  EXPECT_EQ(members[0], at);
  EXPECT_GT((members[1] - members[0]).norm(), 1e-9);
  EXPECT_GT((members[2] - members[1]).norm(), 1e-9);
  // They learned the same robot: each predicts the log a frame ahead within 1.5 times
  // the first's error.
  const auto one_frame_rmse = [&](const OmniPredictor& member) {
    OmniReplayOptions o;
    o.backend = "learned";
    o.backend_options.predictor = std::make_shared<const OmniPredictor>(member);
    o.horizon = 1;
    const OmniReplayResult r = ReplayOmniLog(testing::Omni4(), *log_, o);
    double sum = 0;
    int rows = 0;
    for (std::size_t i = 0; i < log_->rows.size(); ++i) {
      if (!r.predicted[i] || !log_->rows[i].measured) continue;
      sum += std::pow(r.pose[i].x - log_->rows[i].pose.x, 2) + std::pow(r.pose[i].y - log_->rows[i].pose.y, 2);
      ++rows;
    }
    return std::sqrt(sum / std::max(rows, 1));
  };
  const double first = one_frame_rmse(*alone_);
  for (int k = 1; k < 3; ++k) {
    drawn.DrawMember(*ensemble_, k);
    EXPECT_LT(one_frame_rmse(drawn), 1.5 * first) << k;
  }
  EXPECT_THROW(drawn.DrawMember(*ensemble_, 3), std::invalid_argument);

  const std::string dir = testing::TempDir("network_ensemble");
  ensemble_->Save(dir + "/e.pred");
  const OmniPredictor back = OmniPredictor::Load(dir + "/e.pred");
  ASSERT_EQ(back.ensemble().size(), 2u);
  OmniPredictor again = back;
  for (int k = 0; k < 3; ++k) {
    again.DrawMember(back, k);
    EXPECT_EQ(again.PredictDelta(x.data()), members[static_cast<std::size_t>(k)]) << k;
  }
}

// The learned backend's sampled rollouts draw a member each: with the driving noise all
// but off the samples still spread (by the members' disagreement), and without the draws
// they all fall on the prediction, which is the same bit for bit with or without them.
TEST_F(NetworkEnsemble, SampledRolloutsSpreadByTheMembersAlone) {
  const testing::DrawnSpread spread =
      testing::SpreadWithAndWithoutDraws(*log_, testing::QuietLearnedReplay(*ensemble_, 30, 12, 10));
  ASSERT_GT(spread.rows, 20);
  EXPECT_EQ(spread.moved_predictions, 0);
  EXPECT_GT(spread.drawn, 1e-4);  // m: the members' disagreement half a second ahead
  EXPECT_LT(spread.fixed, 1e-3 * spread.drawn);
}

// A residual network (the correction of the model's own prediction) takes an ensemble as
// well: its members correct the same physics, and its sampled rollouts spread by them.
TEST_F(NetworkEnsemble, AResidualNetworkHasOneToo) {
  OmniTrainOptions o;
  o.kind = "mlp";
  o.residual = true;
  o.mlp.hidden = {16};
  o.mlp.max_epochs = 40;
  o.members = 2;
  const OmniPredictor residual = TrainOmniPredictor(testing::Omni4(), {*log_}, o);
  ASSERT_TRUE(residual.residual());
  ASSERT_EQ(residual.ensemble().size(), 1u);
  const testing::DrawnSpread spread =
      testing::SpreadWithAndWithoutDraws(*log_, testing::QuietLearnedReplay(residual, 30, 12, 10));
  ASSERT_GT(spread.rows, 20);
  EXPECT_EQ(spread.moved_predictions, 0);
  EXPECT_GT(spread.drawn, 1e-4);
  EXPECT_LT(spread.fixed, 1e-3 * spread.drawn);
}

// An ensemble is a network's, of one frame ahead, of 1 to 31 further members, each a
// network of the file's layout: anything else is refused at its file, and train refuses
// --members for a linear predictor and beyond 32.
TEST_F(NetworkEnsemble, MalformedEnsemblesAndOptionsAreInputErrors) {
  const std::string dir = testing::TempDir("network_ensemble_bad");
  ensemble_->Save(dir + "/e.pred");
  std::ifstream in(dir + "/e.pred");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto refused = [&](const std::string& edited, const std::string& expected) {
    const std::string path = dir + "/bad.pred";
    std::ofstream(path) << edited;
    try {
      OmniPredictor::Load(path);
      ADD_FAILURE() << "loaded: " << expected;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.pred:"), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find("unknown"), std::string::npos) << "said twice: " << e.what();
    }
  };
  const std::size_t at = text.find("ensemble:");
  ASSERT_NE(at, std::string::npos);
  refused(text.substr(0, at) + "ensemble: 3\n" + text.substr(text.find("\nmlp:", at) + 1), "list of 1 to 31");
  std::string wrong_layers = text;
  const std::size_t layers = wrong_layers.find("layers:", at);
  wrong_layers.replace(layers, wrong_layers.find('\n', layers) - layers, "layers: [42, 16, 4]");
  refused(wrong_layers, "must run from 42 inputs to 3 outputs");
  // Layers whose sizes multiply past an int (and past any real network) are refused, not
  // read past their numbers or allocated.
  std::string huge = text;
  const std::size_t first = huge.find("layers:", at);
  huge.replace(first, huge.find('\n', first) - first, "layers: [42, 46341, 46341, 3]");
  refused(huge, "more than 16777216 numbers");
  std::string linear = text;
  linear.replace(linear.find("kind: mlp"), 9, "kind: linear");
  refused(linear, "only a network");

  OmniTrainOptions o;
  o.members = 2;
  EXPECT_THROW(TrainOmniPredictor(testing::Omni4(), {*log_}, o), InputError);  // linear
  o.kind = "mlp";
  o.members = 33;
  EXPECT_THROW(TrainOmniPredictor(testing::Omni4(), {*log_}, o), InputError);
  o.members = 2;
  o.horizon = 4;
  EXPECT_THROW(TrainOmniPredictor(testing::Omni4(), {*log_}, o), InputError);
}

}  // namespace
}  // namespace twinsim
