#include "backends/arm_backend_factory.h"
#include "backends/learned/learned_arm_backend.h"

#include <gtest/gtest.h>

#include "control/arm_trials.h"
#include "core/error.h"
#include "sim/arm_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace {

ArmPredictor SmallPredictor(const ArmModel& plant, const ArmModel& hat, const std::string& kind) {
  TrainingTrialOptions trials;
  trials.seconds = 3;
  ArmTrainOptions options;
  options.kind = kind;
  options.mlp.hidden = {8};
  options.mlp.max_epochs = 3;
  return TrainArmPredictor(hat, RecordTrainingTrials(plant, hat, trials, 2, 5), options);
}

TEST(LearnedArmBackend, SaveRestoreIsBitExactAndStepsOneSample) {
  const ArmModel plant = LoadArmModel(testing::SourcePath("models/rrr_plant.yaml"));
  const ArmModel hat = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  for (const std::string kind : {"linear", "mlp"}) {
    const ArmPredictor p = SmallPredictor(plant, hat, kind);
    ArmSimulation sim(hat, MakeLearnedArmBackend(hat, p));
    EXPECT_EQ(sim.backend().name(), "learned");
    EXPECT_EQ(sim.physics_substeps(), 1);
    const Eigen::VectorXd q0 = Eigen::Vector3d(0.1, 0.4, -1.0);
    sim.Reset(q0, Eigen::VectorXd::Zero(3));
    const ArmController pd = [&](double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
      return Eigen::VectorXd(40 * (q0 + Eigen::Vector3d::Constant(0.2 * std::sin(5 * t)) - q) - 4 * qd +
                             Eigen::Vector3d(0, 8, 2));
    };
    sim.Run(50, pd);
    const ArmSimulationState saved = sim.Save();
    const ArmTrajectory a = sim.Run(100, pd);
    sim.Restore(saved);
    const ArmTrajectory b = sim.Run(100, pd);
    ASSERT_TRUE(a.q.allFinite());
    EXPECT_EQ(a.q, b.q) << kind;  // bit for bit
    EXPECT_EQ(a.qd, b.qd) << kind;
    EXPECT_GT((a.q.row(99) - a.q.row(0)).norm(), 1e-3) << kind;  // it moves
  }
  // Physics substeps are refused: it steps whole samples. The factory builds it by name.
  const ArmPredictor p = SmallPredictor(plant, hat, "linear");
  ArmBackendOptions options;
  options.physics_substeps = 2;
  options.predictor = std::make_shared<ArmPredictor>(p);
  try {
    MakeArmBackend("learned", hat, options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("steps one whole sample at a time"), std::string::npos) << e.what();
  }
  options.physics_substeps = 0;
  EXPECT_EQ(MakeArmBackend("learned", hat, options)->name(), "learned");
  // A predictor for another arm is refused by the factory.
  EXPECT_THROW(MakeLearnedArmBackend(plant, p), InputError);  // trained for 'rrr', not 'rrr_plant'
}

TEST(LearnedArmBackend, TheLoopAddsNoFrictionOnTop) {
  // The loop's drive torque to a learned backend is the delayed command itself (no
  // torque_offset here, and no friction, which would act after `applied`), even for a
  // model that lists effects: the predictor has learned the real arm's.
  const ArmModel plant = LoadArmModel(testing::SourcePath("models/rrr_plant.yaml"));
  const ArmModel hat = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const ArmPredictor p = SmallPredictor(plant, hat, "linear");
  ArmModel with_effects = hat;
  AddArmEffect({"torque_offset", 1, {{"tau0", 5.0}}}, 3, &with_effects.effects);
  ArmSimulation sim(with_effects, MakeLearnedArmBackend(with_effects, p));
  sim.Reset(Eigen::Vector3d(0, 0.3, -1), Eigen::VectorXd::Zero(3));
  const ArmTrajectory run = sim.Run(5, [](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Eigen::VectorXd(Eigen::Vector3d(1, 2, 3));
  });
  EXPECT_EQ(run.applied(3, 1), 2.0);  // no torque_offset added (D = 1: sample 3 gets the command of 2)
}

}  // namespace
}  // namespace twinsim
