#include "learning/arm_predictor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "backends/arm_backend_factory.h"
#include "backends/learned/learned_arm_backend.h"
#include "control/arm_trials.h"
#include "core/error.h"
#include "core/rng.h"
#include "learning/arm_nominal_step.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_dynamics.h"
#include "sim/arm_simulation.h"
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
  // A network whose numbers read but cannot be used: an InputError naming the file.
  const std::string mlp_head =
      "twinsim_predictor: 1\nrobot: arm\nkind: mlp\nmodel: pendulum\ndof: 1\nsample_time: 0.001\n";
  auto mlp = [](const std::string& output_scale) {
    return "mlp:\n  layers: [4, 2]\n  input_mean: [0, 0, 0, 0]\n  input_scale: [1, 1, 1, 1]\n  output_mean: [0, 0]\n"
           "  output_scale: " + output_scale + "\n  weights0: [0, 0, 0, 0, 0, 0, 0, 0]\n  biases0: [0, 0]\n";
  };
  EXPECT_EQ(error_of(mlp_head + layout + mlp("[1, 1]")), "no error");
  const std::string e5 = error_of(mlp_head + layout + mlp("[0, 1]"));
  EXPECT_NE(e5.find("bad.pred: corrupt neural network: Mlp::FromParameters: output_scale has values <= 0"),
            std::string::npos)
      << e5;
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

// The nominal step is the loop's step over the model (delay taken out): bit for bit, for
// one sample and for several, and a remembered step gives the same bits.
TEST(ArmNominalStep, IsTheLoopsStepBitForBit) {
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const Eigen::Vector3d q(0.1, 0.4, -1.0), qd(0.3, 0.0, -0.5);  // the shoulder at rest: Coulomb holds it
  // The shoulder's torque within 0.3 N·m of what holds it still: its Coulomb friction (1 N·m) does.
  const Eigen::Vector3d hold = InverseDynamics(rrr, q, qd, Eigen::VectorXd::Zero(3), false);
  const Eigen::Vector3d tau0 = hold + Eigen::Vector3d(2, 0.3, 0), tau1 = hold + Eigen::Vector3d(-1, 5, 1),
                        tau2 = hold + Eigen::Vector3d(0.5, -4, 2);
  ArmSimulation sim(rrr, MakeArmBackend("analytic", rrr));  // delay 1: the Reset torque acts first
  sim.Reset(q, qd, tau0);
  int k = 0;
  const Eigen::Vector3d sent[3] = {tau1, tau2, tau2};
  const ArmController controller = [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Eigen::VectorXd(sent[k++]);
  };
  sim.Step(controller);
  const Eigen::VectorXd q1 = sim.backend().q(), qd1 = sim.backend().qd();
  sim.Step(controller);
  sim.Step(controller);
  ArmNominalStep nominal(rrr);
  double taus[9], qa[3], qda[3], qb[3], qdb[3];
  for (int i = 0; i < 3; ++i) taus[i] = tau0[i], taus[3 + i] = tau1[i], taus[6 + i] = tau2[i];
  nominal.Step(q.data(), qd.data(), taus, 1, qa, qda);
  nominal.Step(q.data(), qd.data(), taus, 1, qb, qdb);  // remembered
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(qa[i], q1[i]);
    EXPECT_EQ(qda[i], qd1[i]);
    EXPECT_EQ(qb[i], qa[i]);
    EXPECT_EQ(qdb[i], qda[i]);
  }
  EXPECT_LT(std::abs(qda[1]), 1e-5);  // the shoulder sticks (to the friction solve's tolerance)
  nominal.Step(q.data(), qd.data(), taus, 3, qa, qda);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(qa[i], sim.backend().q()[i]);
    EXPECT_EQ(qda[i], sim.backend().qd()[i]);
  }
}

// A residual predictor trained on an arm that is exactly its nominal model has nothing
// to correct: every target is zero, so it must move exactly as the nominal model's loop
// did, Coulomb sticking included (the same deterministic step in training and in use).
TEST(ArmResidualPredictor, OverAnExactModelIsThatModel) {
  const ArmModel rrr = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  TrainingTrialOptions trials;
  trials.seconds = 2;
  trials.stop_and_go = 1;  // stops: Coulomb friction sticks
  const std::vector<ArmLog> logs = RecordTrainingTrials(rrr, rrr, trials, 1, 21);
  ArmTrainOptions options;
  options.residual = true;
  ArmTrainSummary summary;
  const ArmPredictor p = TrainArmPredictor(rrr, logs, options, &summary);
  EXPECT_TRUE(p.residual());
  EXPECT_TRUE(p.layout().nominal_errors);
  EXPECT_EQ(p.layout().num_inputs(), 48 + 2 * 3 * 3);
  const ArmSequence seq = ToArmSequence(logs[0], p.layout());
  double worst = 0;
  for (int start = 10; start + 200 < seq.rows(); start += 300)
    worst = std::max(worst, ArmRolloutError(p, seq, start, 200).cwiseAbs().maxCoeff());
  std::printf("[measured] residual over an exact model: train RMSE %.3g rad, 200-step rollout error %.3g rad\n",
              summary.train_rmse, worst);
  EXPECT_LT(summary.train_rmse, 1e-15);
  EXPECT_LT(worst, 1e-12);
}

TEST(ArmResidualPredictor, FileRoundTripAttachAndChecks) {
  const ArmModel model = Pendulum();
  const std::vector<ArmLog> logs = {PendulumLog(model, 3, 2)};
  const std::string dir = testing::TempDir("arm_residual_roundtrip");
  for (const std::string kind : {"linear", "mlp"}) {
    ArmTrainOptions options;
    options.kind = kind;
    options.residual = true;
    options.nominal_errors = true;
    options.mlp.hidden = {8};
    options.mlp.max_epochs = 5;
    const ArmPredictor p = TrainArmPredictor(model, logs, options);
    const std::string path = dir + "/r_" + kind + ".pred";
    p.Save(path);
    const std::string text = testing::ReadText(path);
    EXPECT_NE(text.find("twinsim_predictor: 2\n"), std::string::npos);
    EXPECT_NE(text.find("residual: true\n"), std::string::npos);
    EXPECT_NE(text.find("nominal_errors: true"), std::string::npos);
    ArmPredictor back = ArmPredictor::Load(path);
    EXPECT_TRUE(back.residual());
    EXPECT_EQ(back.info().nominal_parameters, p.info().nominal_parameters);
    const double q[4] = {0.1, 0.2, 0.3, 0.4}, qd[4] = {1, 1.5, 2, 2.5}, tau[4] = {1, 2, 3, 4};
    double a[2], b[2];
    p.Predict(q, qd, tau, a, a + 1);
    // Loaded, it needs its nominal model before it can predict.
    EXPECT_THROW(back.Predict(q, qd, tau, b, b + 1), std::logic_error);
    back.AttachModel(model, "the test");
    back.Predict(q, qd, tau, b, b + 1);
    EXPECT_EQ(a[0], b[0]) << kind;
    EXPECT_EQ(a[1], b[1]) << kind;
    back.Save(path + "2");
    EXPECT_EQ(text, testing::ReadText(path + "2"));
    // The learned backend attaches the model itself: same steps from the loaded file.
    auto from_file = MakeLearnedArmBackend(model, ArmPredictor::Load(path));
    auto trained = MakeLearnedArmBackend(model, p);
    for (auto* backend : {from_file.get(), trained.get()}) {
      backend->Reset(Eigen::VectorXd::Constant(1, 0.3), Eigen::VectorXd::Constant(1, 0.5), Eigen::VectorXd::Zero(1));
      Eigen::VectorXd applied;
      for (int k = 0; k < 50; ++k) backend->Step(Eigen::VectorXd::Constant(1, 2.0), &applied);
    }
    EXPECT_EQ(from_file->q()[0], trained->q()[0]) << kind;
    EXPECT_EQ(from_file->qd()[0], trained->qd()[0]) << kind;
  }
  // A model file with other dynamic parameters under the same name is refused.
  const ArmPredictor p = ArmPredictor::Load(dir + "/r_linear.pred");
  ArmModel heavier = model;
  heavier.joints[0].child.mass = 1.1;
  try {
    p.CheckUse(heavier, 1, "the test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("r_linear.pred: residual predictor corrects model 'pendulum' with parameter m1 = 1, "
                                         "this model file has 1.1000000000000001; retrain it for this model (the test)"),
              std::string::npos)
        << e.what();
  }
}

TEST(ArmResidualPredictor, ReadsVersion1AndRefusesInconsistentFiles) {
  const ArmModel model = Pendulum();
  const std::string dir = testing::TempDir("arm_residual_versions");
  const ArmPredictor p = TrainArmPredictor(model, {PendulumLog(model, 2, 6)}, ArmTrainOptions{});
  p.Save(dir + "/v2.pred");
  const std::string v2 = testing::ReadText(dir + "/v2.pred");
  ASSERT_NE(v2.find("twinsim_predictor: 2\nrobot: arm\nkind: linear\nresidual: false\n"), std::string::npos) << v2;
  // The same predictor as version 1 wrote it: no `residual` key.
  std::string v1 = v2;
  v1.replace(v1.find("twinsim_predictor: 2\n"), 21, "twinsim_predictor: 1\n");
  v1.erase(v1.find("residual: false\n"), 16);
  const ArmPredictor old = ArmPredictor::Load(testing::WriteText(dir + "/v1.pred", v1));
  EXPECT_FALSE(old.residual());
  const double q[4] = {0.1, 0.2, 0.3, 0.4}, qd[4] = {1, 1.5, 2, 2.5}, tau[4] = {1, 2, 3, 4};
  double a[2], b[2];
  p.Predict(q, qd, tau, a, a + 1);
  old.Predict(q, qd, tau, b, b + 1);
  EXPECT_EQ(a[0], b[0]);
  EXPECT_EQ(a[1], b[1]);
  auto error_of = [&](const std::string& text) {
    try {
      ArmPredictor::Load(testing::WriteText(dir + "/bad.pred", text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Version 1 knew no residual predictors.
  std::string v1_residual = v1;
  v1_residual.insert(v1_residual.find("model: pendulum"), "residual: true\n");
  const std::string e1 = error_of(v1_residual);
  EXPECT_NE(e1.find("bad.pred:4:1: unknown key 'residual'"), std::string::npos) << e1;
  // A residual file without its nominal model, and a nominal model in a plain one.
  std::string no_nominal = v2;
  no_nominal.replace(no_nominal.find("residual: false"), 15, "residual: true");
  const std::string e2 = error_of(no_nominal);
  EXPECT_NE(e2.find("missing required key 'nominal'"), std::string::npos) << e2;
  std::string stray = v2;
  stray.insert(stray.find("dof: 1"), "nominal: {step: analytic, parameters: [1]}\n");
  const std::string e3 = error_of(stray);
  EXPECT_NE(e3.find("bad.pred:6:10: 'nominal': only a residual predictor (residual: true) has a nominal model"), std::string::npos)
      << e3;
  const std::string e4 = error_of("twinsim_predictor: 3\nrobot: arm\n");
  EXPECT_NE(e4.find("bad.pred:1:20: 'twinsim_predictor': arm predictor format version 3 is not supported (this build reads "
                   "versions 1 to 2)"),
            std::string::npos)
      << e4;
}

TEST(ArmResidualPredictor, TrainingIsDeterministic) {
  const ArmModel model = Pendulum();
  const std::vector<ArmLog> logs = {PendulumLog(model, 2, 7)};
  const std::string dir = testing::TempDir("arm_residual_determinism");
  for (const std::string kind : {"linear", "mlp"}) {
    ArmTrainOptions options;
    options.kind = kind;
    options.residual = true;
    options.mlp.hidden = {8, 8};
    options.mlp.max_epochs = 5;
    TrainArmPredictor(model, logs, options).Save(dir + "/a.pred");
    TrainArmPredictor(model, logs, options).Save(dir + "/b.pred");
    EXPECT_EQ(testing::ReadText(dir + "/a.pred"), testing::ReadText(dir + "/b.pred")) << kind;
  }
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
