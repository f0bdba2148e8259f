// Computed-torque and PD + feedforward tracking of the writing task on the RRR arm
// (seed 001, Fig. 6 and 7): with the right model the one-sample delay is the only error
// left; with the bare arm's model on the loaded arm the errors grow by orders of
// magnitude; the rod with the tip mass drives the shoulder into its effort limit.
#include "control/computed_torque.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "test_util.h"

namespace twinsim {
namespace {

ArmModel Load(const std::string& name) { return LoadArmModel(testing::SourcePath("models/" + name + ".yaml")); }

// The writing task's reference (the same joint path for every load: the IK is kinematic).
const ArmReference& Reference() {
  static const ArmReference ref = WritingTaskReference(Load("rrr"), WritingTaskOptions{});
  return ref;
}

TrackingTrial Trial(const std::string& plant, const std::string& model,
                    TrackingController c = TrackingController::kComputedTorque) {
  TrackingOptions o;
  o.controller = c;
  return RunTrackingTrial(Load(plant), Load(model), Reference(), o);
}

TEST(ComputedTorque, GainsFromTheBandwidth) {
  const TrackingGains g = ComputedTorqueGains(3, 10, 1);
  const double w = 2 * kPi * 10;
  EXPECT_NEAR(g.kp(1), w * w, 1e-9);  // 3947.8 1/s^2
  EXPECT_NEAR(g.kd(2), 2 * w, 1e-12);  // 125.7 1/s
  const ArmModel arm = Load("rrr");
  const Eigen::Vector3d q0(0.2, 0.3, -1.0);
  const TrackingGains pd = PdFeedforwardGains(arm, q0, 10, 0.7);
  const Eigen::VectorXd m = MassMatrix(arm, q0).diagonal();
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(pd.kp(j), m(j) * w * w, 1e-9 * pd.kp(j));
    EXPECT_NEAR(pd.kd(j), m(j) * 2 * 0.7 * w, 1e-9 * pd.kd(j));
  }
  EXPECT_THROW(ComputedTorqueGains(3, 0, 1), std::invalid_argument);
}

TEST(ComputedTorque, LawsAgreeWithTheModelWhenOnTheReference) {
  // On the reference (e = 0) both laws give the model's inverse dynamics, to round-off.
  const ArmModel arm = Load("rrr_rod");
  const Eigen::Vector3d q(0.1, 0.5, -1.2), qd(0.4, -0.8, 1.5), qdd(2.0, 3.0, -4.0);
  const Eigen::VectorXd id = InverseDynamics(arm, q, qd, qdd, true);
  Eigen::VectorXd part;
  const Eigen::VectorXd ct = ComputedTorque(arm, ComputedTorqueGains(3, 10, 1), true, qd, q, qd, qdd, q, qd, &part);
  EXPECT_LT((ct - id).norm(), 1e-12 * id.norm());
  EXPECT_LT((part - id).norm(), 1e-12 * id.norm());
  const Eigen::VectorXd pd = PdFeedforwardTorque(arm, PdFeedforwardGains(arm, q, 10, 1), true, q, qd, qdd, q, qd, &part);
  EXPECT_LT((pd - id).norm(), 1e-12 * id.norm());
  // Off the reference the computed-torque feedback is M (Kp e): 1 mrad on the elbow.
  const Eigen::Vector3d e(0, 0, 1e-3);
  const Eigen::VectorXd off = ComputedTorque(arm, ComputedTorqueGains(3, 10, 1), true, qd, q + e, qd, qdd, q, qd, nullptr);
  const double w = 2 * kPi * 10;
  EXPECT_LT((off - id - MassMatrix(arm, q) * e * w * w).norm(), 1e-9);
}

TEST(ComputedTorque, RejectsBadInput) {
  TrackingOptions o;
  std::string why;
  o.bandwidth = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "bandwidth must be > 0 (Hz)");
  EXPECT_THROW(RunTrackingTrial(Load("rrr"), Load("rrr"), Reference(), o), InputError);
  ArmReference bad = Reference();
  bad.sample_time = 0.002;
  EXPECT_THROW(RunTrackingTrial(Load("rrr"), Load("rrr"), bad, TrackingOptions{}), std::invalid_argument);
  TrackingOptions unknown;
  unknown.backend = "mujoco";
  try {
    RunTrackingTrial(Load("rrr"), Load("rrr"), Reference(), unknown);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown arm backend 'mujoco' (known: analytic, ode, bullet, learned)"),
              std::string::npos)
        << e.what();
  }
  const ArmModel arm = Load("rrr");
  EXPECT_THROW(ComputedTorque(arm, ComputedTorqueGains(3, 10, 1), true, Eigen::Vector2d::Zero(), Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::Zero(), nullptr),
               std::invalid_argument);
}

// With the exact model (plant == model) on the analytic backend what is left is the
// sampled-data implementation: the command is held over each 1 ms sample (and reaches
// the joints one sample late) while the torque the path needs changes within it, and the
// path's acceleration jumps in between samples. Measured max error 6.8e-5 rad (computed
// torque) and 6.1e-5 rad (PD + feedforward) on the bare arm, 6.8e-5 / 4.8e-5 with the
// rod: we assert < 1.5e-4 rad, about twice that. The delay itself is compensated by the
// feedforward's one-sample preview: without the delay the error is 6.4e-5 rad.
TEST(ComputedTorque, ExactModelTracksTheWritingTaskWithinTheSamplingBound) {
  for (const std::string name : {"rrr", "rrr_rod"}) {
    for (auto c : {TrackingController::kComputedTorque, TrackingController::kPdFeedforward}) {
      const TrackingTrial t = Trial(name, name, c);
      EXPECT_LT(t.error_max.maxCoeff(), 1.5e-4) << name << " " << t.BriefReport();
      EXPECT_LT(t.error_rms.maxCoeff(), 3e-5) << name << " " << t.BriefReport();
      EXPECT_EQ(t.saturated_fraction.maxCoeff(), 0) << name << " " << t.BriefReport();
      // The model's torque is nearly all of the command: the feedback's RMS is below 2%
      // of the command's RMS on every joint (measured 0.3% to 1.4%).
      for (int j = 0; j < 3; ++j) {
        EXPECT_LT(t.model_vs_command_rms(j), 0.02 * t.command_rms(j)) << name << " joint " << j + 1;
      }
    }
  }
}

TEST(ComputedTorque, ResidualErrorComesFromSamplingAndDelay) {
  const ArmModel arm = Load("rrr");
  TrackingOptions o;
  const double base = RunTrackingTrial(arm, arm, Reference(), o).error_max.maxCoeff();  // 6.8e-5 rad
  // Without the preview the one-sample delay triples the error (measured 2.0e-4 rad).
  o.preview = 0;
  EXPECT_GT(RunTrackingTrial(arm, arm, Reference(), o).error_max.maxCoeff(), 2.5 * base);
  // Without the delay (and with the preview then 0) it barely changes (6.4e-5 rad)...
  ArmModel no_delay = arm;
  no_delay.delay_samples = 0;
  o.preview = -1;
  const double undelayed = RunTrackingTrial(no_delay, no_delay, Reference(), o).error_max.maxCoeff();
  EXPECT_GT(undelayed, 0.8 * base);
  EXPECT_LT(undelayed, base);
  // ...while sampling 4 times faster cuts it by 3 (2.3e-5 rad at Ts = 0.25 ms).
  ArmModel fast = arm;
  fast.sample_time = 0.00025;
  const ArmReference fast_ref = WritingTaskReference(fast, WritingTaskOptions{});
  EXPECT_LT(RunTrackingTrial(fast, fast, fast_ref, o).error_max.maxCoeff(), 0.45 * base);
  // Feeding forward each sample's mean reference acceleration cuts the error RMS by a
  // third with PD + feedforward (norm over the joints 1.6e-5 -> 1.0e-5 rad).
  o.controller = TrackingController::kPdFeedforward;
  const double pd_rms = RunTrackingTrial(arm, arm, Reference(), o).error_rms.norm();
  o.interval_acceleration = true;
  EXPECT_LT(RunTrackingTrial(arm, arm, Reference(), o).error_rms.norm(), 0.75 * pd_rms);
}

TEST(ComputedTorque, BareModelOnTheRodArmTracksFarWorse) {
  const TrackingTrial exact = Trial("rrr_rod", "rrr_rod");
  const TrackingTrial bare = Trial("rrr_rod", "rrr");
  // Measured: max error 0.0442 rad (elbow) vs 6.8e-5 rad, a ratio of about 650.
  EXPECT_GT(bare.error_max.maxCoeff(), 200 * exact.error_max.maxCoeff());
  EXPECT_GT(bare.error_max(2), 0.03);
  EXPECT_EQ(bare.saturated_fraction.maxCoeff(), 0);  // the rod alone fits the limits
  // The feedback now carries much of the torque: over 40% of the command's RMS on
  // every joint (measured 41%, 63% and 78%).
  for (int j = 0; j < 3; ++j) EXPECT_GT(bare.model_vs_command_rms(j), 0.4 * bare.command_rms(j)) << j;
}

TEST(ComputedTorque, RodWithTipMassSaturatesTheShoulder) {
  // The tip mass takes the shoulder over its 30 N·m limit whichever model is used: the
  // load, not the model, saturates it (measured 18.3% of the samples with either
  // model); the waist never saturates, the elbow at most briefly (0.2% with the bare
  // model's computed torque, 0 with the true model).
  const TrackingTrial exact = Trial("rrr_rod_tip", "rrr_rod_tip");
  const TrackingTrial bare = Trial("rrr_rod_tip", "rrr");
  for (const TrackingTrial* t : {&exact, &bare}) {
    EXPECT_EQ(t->saturated_fraction(0), 0) << t->BriefReport();
    EXPECT_GT(t->saturated_fraction(1), 0.10) << t->BriefReport();
    EXPECT_LT(t->saturated_fraction(1), 0.30) << t->BriefReport();
    EXPECT_LT(t->saturated_fraction(2), 0.01) << t->BriefReport();
    EXPECT_LE(t->command.col(1).cwiseAbs().maxCoeff(), 30.0);  // clamped to the limit
  }
  // Saturation spoils tracking even with the true model: max error 0.17 rad against
  // 6.8e-5 rad without it, and the bare model is no better (0.12 rad).
  EXPECT_GT(exact.error_max(1), 0.05);
  EXPECT_GT(bare.error_max.maxCoeff(), 1000 * Trial("rrr", "rrr").error_max.maxCoeff());
  // The waist, which never saturates, still shows the model's effect: 5.2e-5 rad with
  // the true model, 9.2e-3 rad with the bare one.
  EXPECT_LT(exact.error_max(0), 1.5e-4);
  EXPECT_GT(bare.error_max(0), 50 * exact.error_max(0));
}

TEST(ComputedTorque, WithoutTheLimitTheTipArmTracksLikeTheOthers) {
  // Unclamped (as if the shoulder's motor were stronger) the true model tracks the tip
  // arm as well as the bare one (measured 6.8e-5 rad, peak shoulder demand 32.7 N·m):
  // the error of the saturating trial is the limit's.
  TrackingOptions o;
  o.saturate = false;
  const TrackingTrial t = RunTrackingTrial(Load("rrr_rod_tip"), Load("rrr_rod_tip"), Reference(), o);
  EXPECT_LT(t.error_max.maxCoeff(), 1.5e-4) << t.BriefReport();
  EXPECT_GT(t.demand.col(1).cwiseAbs().maxCoeff(), 30.0);  // it would need more than 30 N·m
  EXPECT_GT(t.saturated_fraction(1), 0.10);                // counted though not clamped
}

TEST(ComputedTorque, TrialsAreRepeatable) {
  const TrackingTrial a = Trial("rrr_rod", "rrr"), b = Trial("rrr_rod", "rrr");
  EXPECT_EQ(a.q, b.q);
  EXPECT_EQ(a.command, b.command);
  EXPECT_EQ(a.needed, b.needed);
}

TEST(ComputedTorque, RealisedMotionNeedsTheAppliedTorque) {
  // The plant's inverse dynamics along the realised motion gives back the torque that
  // was applied: below 4% of each joint's command RMS (measured 2.5% on the waist,
  // whose Coulomb friction meets the joint's reversals, 0.5% and 0.4% on the others).
  // Without the sticking rule in `needed` the waist's difference was 54%: it stands
  // still through every vertical stroke.
  const TrackingTrial t = Trial("rrr", "rrr");
  for (int j = 0; j < 3; ++j) EXPECT_LT(t.needed_vs_applied_rms(j), 0.04 * t.command_rms(j)) << j;
}

TEST(ComputedTorque, OdeAndBulletTrackLikeTheAnalyticBackend) {
  for (const std::string backend : {"ode", "bullet"}) {
    bool built = false;
    for (const std::string& b : AvailableArmEngines()) built = built || b == backend;
    if (!built) continue;
    TrackingOptions o;
    o.backend = backend;
    const TrackingTrial t = RunTrackingTrial(Load("rrr_rod"), Load("rrr_rod"), Reference(), o);
    EXPECT_LT(t.error_max.maxCoeff(), 5e-4) << t.BriefReport();
  }
}

}  // namespace
}  // namespace twinsim
