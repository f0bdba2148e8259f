// `twinsim train` with arm models and arm logs.
#include <gtest/gtest.h>

#include <filesystem>

#include "control/arm_trials.h"
#include "learning/arm_predictor.h"
#include "robots/arm/arm_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(TrainArmCli, TrainsAndRefusesBadInput) {
  const std::string dir = testing::TempDir("train_arm_cli");
  const ArmModel plant = LoadArmModel(testing::SourcePath("models/rrr_plant.yaml"));
  const ArmModel hat = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  TrainingTrialOptions trials;
  trials.seconds = 2;
  const ArmLog log = RecordTrainingTrials(plant, hat, trials, 1, 3)[0];
  WriteArmLog(dir + "/trial.csv", log, true);
  const std::string model = testing::SourcePath("models/rrr.yaml");

  for (const std::string kind : {"linear", "mlp"}) {
    const auto r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/trial.csv --kind " + kind +
                                       " --horizon 1 --epochs 3 --hidden 8 --out " + dir + "/" + kind + ".pred");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(kind + " predictor of arm rrr (3 joints)"), std::string::npos) << r.out;
    const ArmPredictor p = ArmPredictor::Load(dir + "/" + kind + ".pred");
    EXPECT_EQ(p.info().model_name, "rrr");
    EXPECT_EQ(p.layout().history, 4);
    EXPECT_EQ(p.layout().command_lag, 1);
  }
  // Residual (hybrid) predictors, with and without the nominal model's errors as inputs.
  for (const std::string extra : {"--kind linear", "--kind mlp --nominal-errors on"}) {
    const auto r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/trial.csv " + extra +
                                       " --residual --epochs 3 --hidden 8 --out " + dir + "/residual.pred");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" predictor of arm rrr (3 joints), over its nominal model, with its recent errors"),
              std::string::npos)
        << r.out;
    const ArmPredictor p = ArmPredictor::Load(dir + "/residual.pred");
    EXPECT_TRUE(p.residual());
    EXPECT_TRUE(p.layout().nominal_errors);
    EXPECT_NO_THROW(p.CheckUse(hat, 1, "the test"));
  }
  auto r = testing::RunTwinsim("train --model " + model + " --log " + dir +
                               "/trial.csv --nominal-errors off --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--nominal-errors is for residual predictors only (add --residual)"), std::string::npos) << r.err;
  // Omni robots have residual predictors too; an arm's log is still not an omni log.
  r = testing::RunTwinsim("train --model " + testing::SourcePath("models/omni4.yaml") + " --log " + dir +
                          "/trial.csv --residual --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("trial.csv:1: missing column 'x'"), std::string::npos) << r.err;
  // A log of another joint count.
  testing::WriteText(dir + "/two.csv", "t,q1,q2,tau1,tau2\n0,0,0,0,0\n0.001,0,0,0,0\n0.002,0,0,0,0\n0.003,0,0,0,0\n");
  r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/two.csv --kind linear --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("two.csv:1: the log has 2 joints"), std::string::npos) << r.err;
  // Too short for the history.
  testing::WriteText(dir + "/short.csv",
                     "t,q1,q2,q3,tau1,tau2,tau3\n0,0,0,0,0,0,0\n0.001,0,0,0,0,0,0\n0.002,0,0,0,0,0,0\n0.003,0,0,0,0,0,0\n");
  r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/short.csv --kind linear --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("short.csv: log too short: 4 rows"), std::string::npos) << r.err;
  // A bad number names file, line and column.
  testing::WriteText(dir + "/bad.csv", "t,q1,q2,q3,tau1,tau2,tau3\n0,0,0,0,0,0,0\n0.001,0,zero,0,0,0,0\n");
  r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/bad.csv --kind linear --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.csv:3:"), std::string::npos) << r.err;
  // --history 0 and --history with an omni model.
  r = testing::RunTwinsim("train --model " + model + " --log " + dir + "/trial.csv --history 0 --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--history must be 1 to 50"), std::string::npos) << r.err;
  r = testing::RunTwinsim("train --model " + testing::SourcePath("models/omni4.yaml") + " --log " + dir +
                          "/trial.csv --history 3 --out " + dir + "/x.pred");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--history is for arm models only"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.pred"));
}

}  // namespace
}  // namespace twinsim
