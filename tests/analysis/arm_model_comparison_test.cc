#include "analysis/arm_model_comparison.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "backends/arm_backend_factory.h"
#include "backends/learned/learned_arm_backend.h"
#include "control/arm_trials.h"
#include "control/writing_task.h"
#include "sim/arm_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

// The comparison, small enough for the test suite: trained on 3 x 12 s of
// recorded trials on the plant (models/rrr_plant.yaml, nominal model models/rrr.yaml),
// validated on the writing task, which the trials never contain.
class ArmLearningComparison : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    plant_ = new ArmModel(LoadArmModel(testing::SourcePath("models/rrr_plant.yaml")));
    hat_ = new ArmModel(LoadArmModel(testing::SourcePath("models/rrr.yaml")));
    TrainingTrialOptions trials;
    trials.seconds = 12;
    trials.stop_and_go = 0.67;
    logs_ = new std::vector<ArmLog>(RecordTrainingTrials(*plant_, *hat_, trials, 3, 1));
    held_out_ = new ArmLog(RecordTrainingTrials(*plant_, *hat_, trials, 2, 100)[1]);
    ArmTrainOptions linear;
    linear_ = new ArmPredictor(TrainArmPredictor(*hat_, *logs_, linear, &linear_summary_));
    ArmTrainOptions mlp;
    mlp.kind = "mlp";
    mlp.mlp.hidden = {32, 32};
    mlp.mlp.max_epochs = 60;
    mlp.mlp.patience = 15;
    mlp_ = new ArmPredictor(TrainArmPredictor(*hat_, *logs_, mlp, &mlp_summary_));
    linear.residual = true;
    residual_linear_ = new ArmPredictor(TrainArmPredictor(*hat_, *logs_, linear, &residual_linear_summary_));
    mlp.residual = true;
    residual_mlp_ = new ArmPredictor(TrainArmPredictor(*hat_, *logs_, mlp, &residual_mlp_summary_));
  }
  static void TearDownTestSuite() {
    delete plant_, delete hat_, delete logs_, delete held_out_, delete linear_, delete mlp_;
    delete residual_linear_, delete residual_mlp_;
  }
  static ArmModel *plant_, *hat_;
  static std::vector<ArmLog>* logs_;
  static ArmLog* held_out_;
  static ArmPredictor *linear_, *mlp_, *residual_linear_, *residual_mlp_;
  static ArmTrainSummary linear_summary_, mlp_summary_, residual_linear_summary_, residual_mlp_summary_;
};
ArmModel* ArmLearningComparison::plant_ = nullptr;
ArmModel* ArmLearningComparison::hat_ = nullptr;
std::vector<ArmLog>* ArmLearningComparison::logs_ = nullptr;
ArmLog* ArmLearningComparison::held_out_ = nullptr;
ArmPredictor* ArmLearningComparison::linear_ = nullptr;
ArmPredictor* ArmLearningComparison::mlp_ = nullptr;
ArmPredictor* ArmLearningComparison::residual_linear_ = nullptr;
ArmPredictor* ArmLearningComparison::residual_mlp_ = nullptr;

ArmTrainSummary ArmLearningComparison::residual_linear_summary_;
ArmTrainSummary ArmLearningComparison::residual_mlp_summary_;
ArmTrainSummary ArmLearningComparison::linear_summary_;
ArmTrainSummary ArmLearningComparison::mlp_summary_;

TEST_F(ArmLearningComparison, OpenLoopPredictionOnHeldOutTrials) {
  std::printf("[measured] linear: %s\n[measured] mlp: %s\n", linear_summary_.BriefReport().c_str(),
              mlp_summary_.BriefReport().c_str());
  std::printf("[measured] residual linear: %s\n[measured] residual mlp: %s\n",
              residual_linear_summary_.BriefReport().c_str(), residual_mlp_summary_.BriefReport().c_str());
  const int steps = 100;  // 100 ms
  const RolloutStats lin = PredictorRolloutStats(*linear_, *held_out_, 10, held_out_->rows() - 1, steps, 500);
  const RolloutStats mlp = PredictorRolloutStats(*mlp_, *held_out_, 10, held_out_->rows() - 1, steps, 500);
  const RolloutStats rlin =
      PredictorRolloutStats(*residual_linear_, *held_out_, 10, held_out_->rows() - 1, steps, 500);
  const RolloutStats rmlp = PredictorRolloutStats(*residual_mlp_, *held_out_, 10, held_out_->rows() - 1, steps, 500);
  const RolloutStats phys = PhysicalRolloutStats(*hat_, "analytic", *held_out_, 10, held_out_->rows() - 1, steps, 500);
  auto row = [](const char* name, const RolloutStats& s) {
    std::printf("[measured] open loop %-22s one step RMS (urad) %8.3f %8.3f %8.3f | 100 ms RMS (mrad) %8.3f %8.3f %8.3f (%d runs)\n",
                name, s.one_step_rms[0] * 1e6, s.one_step_rms[1] * 1e6, s.one_step_rms[2] * 1e6, s.final_rms[0] * 1e3,
                s.final_rms[1] * 1e3, s.final_rms[2] * 1e3, s.runs);
  };
  row("learned linear", lin);
  row("learned mlp", mlp);
  row("residual linear", rlin);
  row("residual mlp", rmlp);
  row("physical nominal", phys);
  ASSERT_GT(lin.runs, 10);
  // Measured: linear 3.1 / 4.6 / 18.8 mrad after 100 ms, nominal physical 9.1 / 13 / 108.
  for (int j = 0; j < 3; ++j) EXPECT_LT(lin.final_rms[j], 0.7 * phys.final_rms[j]) << "joint " << j + 1;
  EXPECT_TRUE(mlp.final_rms.allFinite());
  EXPECT_LT(mlp.final_rms.maxCoeff(), phys.final_rms.maxCoeff());
  // The residual models over the nominal one. Measured: residual linear 1.5 / 2.3 / 8.1
  // mrad (0.17 / 0.18 / 0.07 of the nominal model's, about half the pure linear model's);
  // residual MLP 2.0 / 2.5 / 11.4.
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(rlin.final_rms[j], 0.3 * phys.final_rms[j]) << "joint " << j + 1;
    EXPECT_LT(rlin.final_rms[j], 0.8 * lin.final_rms[j]) << "joint " << j + 1;
    EXPECT_LT(rmlp.final_rms[j], 0.5 * phys.final_rms[j]) << "joint " << j + 1;
  }
}

TEST_F(ArmLearningComparison, LearnedBeatsTheNominalModelOnTheWritingTask) {
  const ArmReference ref = WritingTaskReference(*hat_, WritingTaskOptions{});
  TrackingOptions options;  // computed torque over the nominal model, as in docs/writing_task.md
  std::vector<ArmCandidate> candidates;
  for (const std::string& b : AvailableArmEngines())
    candidates.push_back({"physical nominal (" + b + ")", *hat_, [&, b] { return MakeArmBackend(b, *hat_); }});
  candidates.push_back({"learned linear", *hat_, [&] { return MakeLearnedArmBackend(*hat_, *linear_); }});
  candidates.push_back({"learned mlp", *hat_, [&] { return MakeLearnedArmBackend(*hat_, *mlp_); }});
  candidates.push_back({"residual linear", *hat_, [&] { return MakeLearnedArmBackend(*hat_, *residual_linear_); }});
  candidates.push_back({"residual mlp", *hat_, [&] { return MakeLearnedArmBackend(*hat_, *residual_mlp_); }});
  const WritingComparison c = CompareOnReference(*plant_, *hat_, ref, candidates, options);
  std::printf("[measured] writing task, %g s, candidates against the plant:\n%s", ref.t.size() * hat_->sample_time,
              c.FullReport().c_str());
  const ModelGap& nominal = c.gaps[0];  // analytic
  const ModelGap& linear = c.gaps[c.gaps.size() - 4];
  const ModelGap& mlp = c.gaps[c.gaps.size() - 3];
  ASSERT_TRUE(nominal.finite);
  ASSERT_TRUE(linear.finite);
  ASSERT_TRUE(mlp.finite);
  // Measured: the worst joint (the elbow, with the Stribeck friction and the payload the
  // nominal model lacks) 4.7 mrad RMS learned linear against 6.1 mrad nominal physical.
  // The small test-sized network does not beat it (5.7 mrad; docs/arm_learning.md).
  EXPECT_LT(linear.q_rms.maxCoeff(), 0.9 * nominal.q_rms.maxCoeff());
  EXPECT_LT(mlp.q_rms.maxCoeff(), 0.03);
  // The residual models beat the nominal model on every joint. Measured (waist, shoulder,
  // elbow, mrad RMS): nominal 0.84 / 0.63 / 6.11, residual linear 0.65 / 0.46 / 2.82
  // (0.76 / 0.74 / 0.46 of it), residual MLP 0.53 / 0.43 / 2.40 (0.62 / 0.69 / 0.39;
  // other seeds of the small network 0.52-0.71 / 0.58-0.65 / 0.47-0.54).
  const ModelGap& residual_linear = c.gaps[c.gaps.size() - 2];
  const ModelGap& residual_mlp = c.gaps.back();
  ASSERT_TRUE(residual_linear.finite);
  ASSERT_TRUE(residual_mlp.finite);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(residual_linear.q_rms[j], 0.9 * nominal.q_rms[j]) << "joint " << j + 1;
    EXPECT_LT(residual_mlp.q_rms[j], 0.9 * nominal.q_rms[j]) << "joint " << j + 1;
  }
  EXPECT_LT(residual_linear.q_rms.maxCoeff(), 0.6 * nominal.q_rms.maxCoeff());
  EXPECT_LT(residual_mlp.q_rms.maxCoeff(), 0.6 * nominal.q_rms.maxCoeff());
}

TEST_F(ArmLearningComparison, FreeRunStaysBounded) {
  // 5 s with no torque from a raised posture: the learned arm falls and swings like the
  // plant does, finitely; its joints stay within the plant's speeds (x 1.5).
  const Eigen::VectorXd q0 = Eigen::Vector3d(0.2, 0.4, -1.0), zero = Eigen::VectorXd::Zero(3);
  const ArmController none = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Eigen::VectorXd::Zero(3);
  };
  ArmSimulation plant(*plant_, MakeArmBackend("analytic", *plant_));
  plant.Reset(q0, zero);
  const ArmTrajectory p = plant.Run(5000, none);
  for (const ArmPredictor* pred : {linear_, mlp_, residual_linear_, residual_mlp_}) {
    ArmSimulation learned(*hat_, MakeLearnedArmBackend(*hat_, *pred));
    learned.Reset(q0, zero);
    const ArmTrajectory l = learned.Run(5000, none);
    ASSERT_TRUE(l.q.allFinite());
    std::printf("[measured] free run %s%s: max |qd| %.2f rad/s (plant %.2f), |q - q_plant| after 0.2 s %.4f rad, max %.3f rad\n",
                pred->residual() ? "residual " : "", pred->info().kind.c_str(), l.qd.cwiseAbs().maxCoeff(), p.qd.cwiseAbs().maxCoeff(),
                (l.q.row(200) - p.q.row(200)).cwiseAbs().maxCoeff(), (l.q - p.q).cwiseAbs().maxCoeff());
    if (pred != linear_) {
      EXPECT_LT(l.qd.cwiseAbs().maxCoeff(), 1.5 * p.qd.cwiseAbs().maxCoeff());
    }
  }
}

}  // namespace
}  // namespace twinsim
