// ILC as seed 001 designs it (issue 17): FRFs at a grid of postures with coherence, the
// nominal FRF, the learning filter from the known feedback plus the plant's fitted
// inertia and delay, Q's cutoff from the convergence criterion, and learning at gain 1
// on the shipped scenes.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "control/closed_loop_frf.h"
#include "control/computed_torque.h"
#include "control/iterative_learning.h"
#include "core/error.h"
#include "scene/arm_scene.h"
#include "scene/ilc_scene.h"
#include "test_util.h"
#include "control/turntable.h"

namespace twinsim {
namespace {

using testing::SourcePath;

using testing::Turntable;
constexpr double kJ = testing::kTurntableInertia;  // kg m^2

TrackingOptions Pd() { return testing::TurntablePd(); }

ClosedLoopFrf TurntableFrf() {
  FrfOptions fo;
  fo.period = 0.5, fo.periods = 2, fo.f_min = 2, fo.f_max = 200;
  const ArmModel arm = Turntable();
  return MeasureProcessSensitivity(arm, arm, {Eigen::VectorXd::Constant(1, 0.0), Eigen::VectorXd::Constant(1, 1.0)},
                                   Pd(), fo);
}

TEST(IlcSeedFrf, NoiseFreeLinearPlantHasCoherenceOneAndTheNominalIsTheAverage) {
  const ClosedLoopFrf frf = TurntableFrf();
  ASSERT_EQ(frf.coherence.size(), 1u);
  ASSERT_EQ(frf.coherence[0].size(), 2u);
  EXPECT_GT(frf.WorstCoherence(0).minCoeff(), 1 - 1e-9);
  const Eigen::VectorXcd nominal = frf.Nominal(0);
  for (Eigen::Index i = 0; i < nominal.size(); ++i) {
    EXPECT_LT(std::abs(nominal[i] - 0.5 * (frf.response[0][0][i] + frf.response[0][1][i])), 1e-15);
  }
}

TEST(IlcSeedFrf, GridPosturesSpanTwoJointsEndToEndWithinTheLimits) {
  const ArmModel arm = LoadArmModel(SourcePath("models/rrr.yaml"));
  const Eigen::Vector3d base(0.2, 0, 0), low(0, 0.1, -3), high(0, 0.7, 3);
  const std::vector<Eigen::VectorXd> p = GridPostures(arm, base, 1, 2, 4, low, high);
  ASSERT_EQ(p.size(), 16u);
  EXPECT_DOUBLE_EQ(p[0][0], 0.2);
  EXPECT_DOUBLE_EQ(p[0][1], 0.1);
  EXPECT_DOUBLE_EQ(p[15][1], 0.7);
  EXPECT_NEAR(p[5][1], 0.3, 1e-12);
  // The elbow's +-3 rad is beyond its +-150 degrees: clamped.
  EXPECT_NEAR(p[0][2], arm.joints[2].lower, 1e-12);
  EXPECT_NEAR(p[3][2], arm.joints[2].upper, 1e-12);
  EXPECT_THROW(GridPostures(arm, base, 1, 1, 4, low, high), std::invalid_argument);
}

// The known feedback plus a fitted inertia and delay inverts the turntable's PS: the
// inertia is the link's, the delay the model's, PS L = 1 within 5 % to 50 Hz.
TEST(IlcSeedFilter, PlantFitRecoversTheInertiaAndDelayGivenTheFeedback) {
  const ArmModel arm = Turntable();
  const ClosedLoopFrf frf = TurntableFrf();
  LearningFilter feedback = ModelLearningFilter(arm, Pd(), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), 0);
  feedback.inertia = feedback.inertia_early = 123;  // replaced by the fit
  PlantFitOptions fit;
  fit.f_min = 2, fit.f_max = 100, fit.max_shift = 4;
  const LearningFilter l = FitPlantLearningFilter(frf, 0, feedback, 0.0, fit);
  EXPECT_EQ(l.shift, 1);
  EXPECT_NEAR(l.inertia + l.inertia_early, kJ, 0.03 * kJ);
  EXPECT_DOUBLE_EQ(l.damping, feedback.damping);
  EXPECT_DOUBLE_EQ(l.stiffness, feedback.stiffness);
  EXPECT_EQ(l.lines, 50);
  EXPECT_DOUBLE_EQ(l.band_min, 2);
  EXPECT_DOUBLE_EQ(l.band_max, 100);
  for (Eigen::Index i = 0; i < frf.frequency.size() && frf.frequency[i] <= 50; ++i) {
    for (int p = 0; p < 2; ++p) {
      EXPECT_LT(std::abs(frf.response[0][p][i] * l.Response(frf.frequency[i], arm.sample_time) - 1.0), 0.05)
          << frf.frequency[i] << " Hz";
    }
  }
  // Lines below the coherence asked for are not fitted: with every line at 0.5, none is.
  ClosedLoopFrf noisy = frf;
  for (Eigen::VectorXd& c : noisy.coherence[0]) c.setConstant(0.5);
  EXPECT_THROW(FitPlantLearningFilter(noisy, 0, feedback, 0.0, fit), InputError);
  fit.min_coherence = 0.4;
  EXPECT_EQ(FitPlantLearningFilter(noisy, 0, feedback, 0.0, fit).lines, 50);
  fit.min_coherence = 1.5;  // not a coherence
  EXPECT_THROW(FitPlantLearningFilter(frf, 0, feedback, 0.0, fit), InputError);
}

// A joint driven through a series spring, seen at the link (closed form): motor J_m and
// link J_l coupled by k and d, one sample of delay and the zero-order hold of a sampled
// controller, under PD. Neglecting d its inverse is (J_m + J_l) s^2 + (J_m J_l / k) s^4:
// the fourth-order fit finds the snap term and fits the band below the 116 Hz resonance
// better than the rigid one.
TEST(IlcSeedFilter, FourthOrderFitFindsTheSeriesSpring) {
  constexpr double kJm = 0.01, kJl = 0.18, kK = 5000, kD = 0.2;  // kg m^2, N·m/rad, N·m·s/rad
  constexpr double kTs = 0.001, kKp = 1200, kKd = 40;             // s, N·m/rad, N·m·s/rad
  ClosedLoopFrf frf;
  frf.sample_time = kTs;
  frf.frequency = Eigen::VectorXd::LinSpaced(100, 2, 200);
  frf.postures = {Eigen::VectorXd::Zero(1)};
  Eigen::VectorXcd ps(frf.frequency.size());
  for (Eigen::Index i = 0; i < ps.size(); ++i) {
    const std::complex<double> s(0, 2 * M_PI * frf.frequency[i]);
    const std::complex<double> hold = (1.0 - std::exp(-s * kTs)) / (s * kTs);  // zero-order hold
    const std::complex<double> p = (kK + kD * s) / (kJm * kJl * s * s * s * s + (kJm + kJl) * (kK + kD * s) * s * s) *
                                   std::exp(-s * kTs) * hold;
    ps[i] = p / (1.0 + p * (kKp + kKd * s));
  }
  frf.response = {{ps}};
  frf.coherence = {{Eigen::VectorXd::Ones(ps.size())}};
  LearningFilter feedback;
  feedback.damping = kKd, feedback.stiffness = kKp;
  PlantFitOptions fit;  // 2-80 Hz
  const LearningFilter rigid = FitPlantLearningFilter(frf, 0, feedback, 0.0, fit);
  fit.order = 4;
  const LearningFilter spring = FitPlantLearningFilter(frf, 0, feedback, 0.0, fit);
  EXPECT_EQ(rigid.order, 2);
  EXPECT_EQ(rigid.snap, 0);
  EXPECT_EQ(spring.order, 4);
  EXPECT_EQ(spring.shift, 1);
  EXPECT_NEAR(spring.snap, kJm * kJl / kK, 0.15 * kJm * kJl / kK);
  EXPECT_NEAR(spring.inertia + spring.inertia_early, kJm + kJl, 0.03 * (kJm + kJl));
  EXPECT_LT(spring.residual, 0.2 * rigid.residual) << rigid.residual << " " << spring.residual;
  // Both inertias and the snap stay >= 0; the order must be 2 or 4.
  EXPECT_GE(spring.inertia, 0);
  EXPECT_GE(spring.inertia_early, 0);
  fit.order = 3;
  EXPECT_THROW(FitPlantLearningFilter(frf, 0, feedback, 0.0, fit), InputError);
}

// Where |1 - PS L| < 1 everywhere the criterion allows any cutoff: the highest, half the
// highest measured line. Where it does not, the cutoff keeps every product below 1.
TEST(IlcSeedFilter, AutoCutoffIsTheHighestMeetingTheCriterion) {
  const ArmModel arm = Turntable();
  const ClosedLoopFrf frf = TurntableFrf();
  const LearningFilter exact = ModelLearningFilter(arm, Pd(), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), 0);
  IlcOptions o;
  o.gain = 1;
  double worst = 0;
  EXPECT_DOUBLE_EQ(AutoQCutoff(frf, 0, exact, o, &worst), 100);
  EXPECT_LT(worst, 1);
  // An L with three times the inertia: |1 - PS L| -> 2 at high frequencies.
  LearningFilter heavy = exact;
  heavy.inertia *= 3, heavy.inertia_early *= 3;
  ASSERT_GT(LearningLimitFrequency(frf, 0, heavy, 1), 2);
  const double cutoff = AutoQCutoff(frf, 0, heavy, o, &worst);
  EXPECT_LT(cutoff, 100);
  EXPECT_LT(worst, 1);
  o.q_cutoff = cutoff;
  EXPECT_LT(ConvergenceFactor(frf, 0, heavy, o).maxCoeff(), 1);
  o.q_cutoff = cutoff + 0.5;
  EXPECT_GE(ConvergenceFactor(frf, 0, heavy, o).maxCoeff(), 1);
  // Per-joint cutoffs are the ones used.
  IlcOptions per_joint;
  per_joint.q_cutoffs = {cutoff};
  EXPECT_DOUBLE_EQ(per_joint.Cutoff(0), cutoff);
  EXPECT_DOUBLE_EQ(per_joint.Cutoff(1), per_joint.q_cutoff);
}

// The shipped writing scene as the issue asks: gain 1, q_cutoff auto, 16 postures; every
// joint's RMS error at least 10 times lower within 7 trials.
TEST(IlcSeedScene, ShippedSceneLearnsAtGainOneTenfoldWithinSevenTrials) {
  const ArmScene scene = LoadArmScene(SourcePath("scenes/rrr_writing_ilc.yaml"));
  ASSERT_EQ(scene.ilc.options.gain, 1);
  ASSERT_TRUE(scene.ilc.q_cutoff_auto);
  const IlcSceneRun run = RunIlcScene(scene, "", 7);
  EXPECT_EQ(run.postures.size(), 16u);
  ASSERT_EQ(run.options.q_cutoffs.size(), 3u);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(ConvergenceFactor(run.frf, j, run.filters[static_cast<std::size_t>(j)], run.options).maxCoeff(), 1);
    EXPECT_GE(run.result.error_rms[0][j] / run.result.error_rms[7][j], 10) << "joint " << j + 1 << "\n"
                                                                           << run.result.FullReport();
  }
}

// The flexible elbow with q_cutoff auto: the elbow's cutoff lies below its 118 Hz
// resonance and learning does not diverge over 20 trials.
TEST(IlcSeedScene, FlexibleElbowAutoCutoffBelowTheResonanceNoDivergenceIn20Trials) {
  const ArmScene scene = LoadArmScene(SourcePath("scenes/rrr_writing_ilc_flex.yaml"));
  const IlcSceneRun run = RunIlcScene(scene, "", 20);
  ASSERT_EQ(run.options.q_cutoffs.size(), 3u);
  EXPECT_LT(run.options.q_cutoffs[2], 118);
  for (int k = 1; k <= 20; ++k) {
    EXPECT_LT(run.result.WorstRms(k), run.result.WorstRms(0)) << "trial " << k << "\n" << run.result.FullReport();
  }
  EXPECT_FALSE(run.result.Diverged());
}

}  // namespace
}  // namespace twinsim
