#include "learning/arm_predictor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "backends/arm/arm_backend.h"
#include "core/arm_simulation.h"
#include "core/error.h"
#include "core/rng.h"
#include "learning/arm_trials.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_dynamics.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A pendulum swinging in the base x-y plane (gravity along -y, joint axis z) with
// viscous friction: qdd = (tau - m g l cos q - b qd) / I, linear in the features
// (cos q, qd, tau), so ridge regression must recover its one-step map.
constexpr char kPendulum[] = R"(
robot: arm
name: pendulum
sample_time: 0.001
delay_samples: 1
gravity: [0, -9.81, 0]
dh: standard
joints:
  - name: hinge
    type: revolute
    a: 0.5
    alpha_deg: 0
    d: 0
    theta_deg: 0
    viscous: 0.2
    link:
      name: rod
      mass: 1.0
      com: [-0.25, 0, 0]
      inertia: [0.001, 0.02, 0.02, 0, 0, 0]
)";

ArmModel Pendulum() { return LoadArmModelFromYamlString(kPendulum, "pendulum"); }

// The pendulum driven by random torques held 20 ms around its holding torque, from
// `seconds` of 1 kHz samples: the log its controller would write.
ArmLog PendulumLog(const ArmModel& model, double seconds, std::uint64_t seed) {
  ArmSimulation sim(model, MakeArmBackend("analytic", model));
  sim.Reset(Eigen::VectorXd::Constant(1, 0.3), Eigen::VectorXd::Zero(1));
  Rng rng(seed);
  double held = 0;
  int k = 0;
  const ArmController controller = [&](double, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    if (k++ % 20 == 0) held = rng.Gaussian(1.5);
    // Gravity compensation plus a weak spring to 0.3 rad keeps the motion bounded.
    const double g = InverseDynamics(model, q, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), false)[0];
    return Eigen::VectorXd::Constant(1, g + 3 * (0.3 - q[0]) - 0.5 * qd[0] + held);
  };
  const ArmTrajectory run = sim.Run(static_cast<int>(seconds / model.sample_time), controller);
  ArmLog log;
  log.path = "pendulum" + std::to_string(seed) + ".csv";
  log.dof = 1;
  log.t = run.t, log.q = run.q, log.qd = run.qd, log.tau = run.command, log.qdd = run.qd * 0;
  log.qd_logged = log.qdd_logged = true;
  log.sample_period = model.sample_time;
  return log;
}

TEST(ArmFeatures, LayoutAndEncoding) {
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const ArmFeatureLayout l = ArmLayoutFor(rrr, 4, 1);
  EXPECT_EQ(l.joints, "RRR");
  EXPECT_EQ(l.command_lag, 1);
  EXPECT_EQ(l.per_sample(), 12);  // 3 x (sin, cos) + 3 qd + 3 tau
  EXPECT_EQ(l.num_inputs(), 48);
  EXPECT_EQ(l.num_outputs(), 6);
  // Encode -> decode gives the later state back exactly (to rounding).
  const double q[3] = {0.1, -0.2, 0.3}, qd[3] = {1, 2, -3}, q2[3] = {0.1011, -0.1979, 0.2969}, qd2[3] = {1.1, 2.1, -3.2};
  double y[6], qb[3], qdb[3];
  EncodeArmOutputs(l, q, qd, q2, qd2, y);
  EXPECT_NEAR(y[0], 0.1011 - 0.1 - 0.001, 1e-15);
  DecodeArmOutputs(l, y, q, qd, qb, qdb);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(qb[i], q2[i], 1e-15);
    EXPECT_NEAR(qdb[i], qd2[i], 1e-15);
  }
  double tau[12] = {}, x[48];
  double qs[12] = {}, qds[12] = {};
  qs[9] = 0.5;
  tau[11] = 7;
  EncodeArmInputs(l, qs, qds, tau, x);
  EXPECT_NEAR(x[36], std::sin(0.5), 1e-15);  // newest sample, joint 1
  EXPECT_NEAR(x[37], std::cos(0.5), 1e-15);
  EXPECT_EQ(x[47], 7);                        // newest torque of joint 3
}

TEST(ArmPredictor, LinearRecoversThePendulumsOneStepMap) {
  const ArmModel model = Pendulum();
  const std::vector<ArmLog> logs = {PendulumLog(model, 20, 1)};
  ArmTrainOptions options;
  options.history = 1;
  ArmTrainSummary summary;
  const ArmPredictor p = TrainArmPredictor(model, logs, options, &summary);
  // Held out, against the analytic arm's own step from the same state and torque.
  const ArmLog test = PendulumLog(model, 2, 99);
  auto backend = MakeArmBackend("analytic", model);
  double worst_qd = 0, worst_q = 0, scale = 0;
  for (int k = 1; k + 1 < test.rows(); k += 7) {
    const double q = test.q(k, 0), qd = test.qd(k, 0), tau = test.tau(k - 1, 0);
    // The true step: rigid body plus the loop's viscous friction, as ArmSimulation does it.
    ArmSimulation sim(model, MakeArmBackend("analytic", model));
    sim.Reset(Eigen::VectorXd::Constant(1, q), Eigen::VectorXd::Constant(1, qd), Eigen::VectorXd::Constant(1, tau));
    sim.Step([](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return Eigen::VectorXd::Zero(1); });
    double qn, qdn;
    p.Predict(&q, &qd, &tau, &qn, &qdn);
    worst_q = std::max(worst_q, std::abs(qn - sim.backend().q()[0]));
    worst_qd = std::max(worst_qd, std::abs(qdn - sim.backend().qd()[0]));
    scale = std::max(scale, std::abs(sim.backend().qd()[0] - qd));
  }
  std::printf("[measured] pendulum: one-step |dq| %.3g rad, |dqd| %.3g rad/s (largest qd change %.3g); %s\n",
              worst_q, worst_qd, scale, summary.BriefReport().c_str());
  // The map is linear in (cos q, qd, tau) up to RK4's O(Ts^2) terms: within 1e-3 of the
  // velocity change and 1e-8 rad.
  EXPECT_LT(worst_qd, 1e-3 * scale);
  EXPECT_LT(worst_q, 1e-8);
  EXPECT_LT(summary.validation_rmse, 1e-8);
}

TEST(ArmPredictor, FileRoundTripIsExact) {
  const ArmModel model = Pendulum();
  const std::vector<ArmLog> logs = {PendulumLog(model, 3, 2)};
  const std::string dir = testing::TempDir("arm_predictor_roundtrip");
  for (const std::string kind : {"linear", "mlp"}) {
    ArmTrainOptions options;
    options.kind = kind;
    options.mlp.hidden = {8};
    options.mlp.max_epochs = 5;
    const ArmPredictor p = TrainArmPredictor(model, logs, options);
    const std::string path = dir + "/p_" + kind + ".pred";
    p.Save(path);
    const ArmPredictor back = ArmPredictor::Load(path);
    EXPECT_EQ(back.info().kind, kind);
    EXPECT_EQ(back.info().model_name, "pendulum");
    EXPECT_EQ(back.layout().joints, "R");
    EXPECT_EQ(back.layout().history, 4);
    EXPECT_EQ(back.info().validation_rmse, p.info().validation_rmse);
    const double q[4] = {0.1, 0.2, 0.3, 0.4}, qd[4] = {1, 1.5, 2, 2.5}, tau[4] = {1, 2, 3, 4};
    double a[2], b[2];
    p.Predict(q, qd, tau, a, a + 1);
    back.Predict(q, qd, tau, b, b + 1);
    EXPECT_EQ(a[0], b[0]) << kind;
    EXPECT_EQ(a[1], b[1]) << kind;
    // Saving what was loaded gives the same bytes.
    back.Save(path + "2");
    EXPECT_EQ(testing::ReadText(path), testing::ReadText(path + "2"));
  }
}

TEST(ArmPredictor, BadFilesNameFileAndLine) {
  const std::string dir = testing::TempDir("arm_predictor_bad");
  auto error_of = [&](const std::string& text) {
    const std::string path = testing::WriteText(dir + "/bad.pred", text);
    try {
      ArmPredictor::Load(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head =
      "twinsim_predictor: 1\nrobot: arm\nkind: linear\nmodel: pendulum\ndof: 1\nsample_time: 0.001\n";
  const std::string layout = "layout: {joints: R, history: 1, horizon: 1, command_lag: 1, inputs: 4, outputs: 2}\n";
  const std::string linear =
      "linear:\n  input_mean: [0, 0, 0, 0]\n  input_scale: [1, 1, 1, 1]\n  weights: [0, 0, 0, 0, 0, 0, 0, 0]\n  bias: [0, 0]\n";
  EXPECT_EQ(error_of(head + layout + linear), "no error");
  EXPECT_NE(error_of(head + "layout: {joints: R, history: 1, horizon: 1, command_lag: 1, inputs: 5, outputs: 2}\n" + linear)
                .find("bad.pred:7:"),
            std::string::npos);
  EXPECT_NE(error_of(head + layout + linear).find("no error"), std::string::npos);
  const std::string short_weights = "linear:\n  input_mean: [0, 0, 0, 0]\n  input_scale: [1, 1, 1, 1]\n  weights: [0, 0]\n  bias: [0, 0]\n";
  const std::string e1 = error_of(head + layout + short_weights);
  EXPECT_NE(e1.find("bad.pred:11:"), std::string::npos) << e1;
  EXPECT_NE(e1.find("weights"), std::string::npos) << e1;
  const std::string e2 = error_of("twinsim_predictor: 7\nrobot: arm\n");
  EXPECT_NE(e2.find("bad.pred:1:"), std::string::npos) << e2;
  EXPECT_NE(e2.find("version 7 is not supported"), std::string::npos) << e2;
  const std::string e3 = error_of(head + "layout: {joints: RX, history: 1, horizon: 1, command_lag: 1, inputs: 4, outputs: 2}\n" + linear);
  EXPECT_NE(e3.find("bad.pred:7:"), std::string::npos) << e3;
  EXPECT_NE(e3.find("R (revolute) or P (prismatic)"), std::string::npos) << e3;
  const std::string e4 = error_of(head + layout + linear + "colour: blue\n");
  EXPECT_NE(e4.find("unknown key 'colour'"), std::string::npos) << e4;
  // An omni robot's predictor is refused as such, and an arm's by the omni reader.
  try {
    ArmPredictor::Load(testing::SourcePath("models/predictors/omni4_h4.pred"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("omni4_h4.pred:1: this is a predictor for an omni robot, not for an arm"),
              std::string::npos)
        << e.what();
  }
  const std::string arm_file = testing::WriteText(dir + "/arm.pred", head + layout + linear);
  try {
    OmniPredictor::Load(arm_file);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("arm.pred:2: this is a predictor for an arm, not for an omni robot"),
              std::string::npos)
        << e.what();
  }
}

TEST(ArmPredictor, CheckUseRefusesAnotherArm) {
  const ArmModel model = Pendulum();
  const ArmPredictor p = TrainArmPredictor(model, {PendulumLog(model, 2, 3)}, ArmTrainOptions{});
  EXPECT_NO_THROW(p.CheckUse(model, 1, "test"));
  auto message = [&](const ArmModel& m, int horizon) {
    try {
      p.CheckUse(m, horizon, "the test");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ArmModel renamed = model;
  renamed.name = "other";
  EXPECT_NE(message(renamed, 1).find("trained for arm model 'pendulum', not 'other'"), std::string::npos);
  ArmModel slow = model;
  slow.sample_time = 0.002;
  EXPECT_NE(message(slow, 1).find("sample time of 0.001 s, model 'pendulum' has 0.002 s"), std::string::npos);
  ArmModel late = model;
  late.delay_samples = 3;
  EXPECT_NE(message(late, 1).find("delay of 1 samples, model 'pendulum' has 3"), std::string::npos);
  EXPECT_NE(message(model, 2).find("predicts 1 sample(s) ahead, the test needs 2"), std::string::npos);
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  ArmModel rrr_named = rrr;
  rrr_named.name = "pendulum";
  EXPECT_NE(message(rrr_named, 1).find("trained for 1 joints (R), model 'pendulum' has 3 (RRR)"), std::string::npos)
      << message(rrr_named, 1);
}

TEST(ArmPredictor, TrainingRefusesBadLogs) {
  const ArmModel model = Pendulum();
  ArmLog tiny = PendulumLog(model, 0.008, 4);
  try {
    TrainArmPredictor(model, {tiny}, ArmTrainOptions{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("log too short: 8 rows"), std::string::npos) << e.what();
  }
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  try {
    TrainArmPredictor(rrr, {PendulumLog(model, 1, 4)}, ArmTrainOptions{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the log has 1 joint (q1, tau1) but the model 'rrr'"), std::string::npos) << e.what();
  }
  ArmLog slow = PendulumLog(model, 1, 4);
  slow.sample_period = 0.002;
  try {
    TrainArmPredictor(model, {slow}, ArmTrainOptions{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample period 0.002 s differs"), std::string::npos) << e.what();
  }
}

TEST(ArmPredictor, TrainingIsDeterministic) {
  const ArmModel model = Pendulum();
  const std::vector<ArmLog> logs = {PendulumLog(model, 3, 5)};
  ArmTrainOptions options;
  options.kind = "mlp";
  options.mlp.hidden = {8, 8};
  options.mlp.max_epochs = 8;
  const std::string dir = testing::TempDir("arm_predictor_determinism");
  TrainArmPredictor(model, logs, options).Save(dir + "/a.pred");
  TrainArmPredictor(model, logs, options).Save(dir + "/b.pred");
  EXPECT_EQ(testing::ReadText(dir + "/a.pred"), testing::ReadText(dir + "/b.pred"));
}

TEST(ArmTrials, RecordingIsDeterministicAndCoversTheWorkspace) {
  const ArmModel plant = LoadArmModel(testing::SourcePath("models/rrr_plant.yaml"));
  const ArmModel hat = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  TrainingTrialOptions options;
  options.seconds = 2;
  const std::vector<ArmLog> a = RecordTrainingTrials(plant, hat, options, 2, 11);
  const std::vector<ArmLog> b = RecordTrainingTrials(plant, hat, options, 2, 11);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(FormatArmLog(a[0], true), FormatArmLog(b[0], true));
  EXPECT_EQ(FormatArmLog(a[1], true), FormatArmLog(b[1], true));
  EXPECT_NE(FormatArmLog(a[0], true), FormatArmLog(a[1], true));
  // Tracking with the dither: within 0.1 rad of the reference, and moving.
  const double err = (a[0].q - a[0].qref).cwiseAbs().maxCoeff();
  EXPECT_LT(err, 0.1);
  EXPECT_GT(a[0].qd.cwiseAbs().maxCoeff(), 0.3);
}

}  // namespace
}  // namespace twinsim
