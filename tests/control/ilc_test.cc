// Iterative learning control: feedforward injection, the closed-loop process
// sensitivity against its closed form, the fitted learning filter, and learning on the
// writing task with model error.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "control/closed_loop_frf.h"
#include "control/computed_torque.h"
#include "control/iterative_learning.h"
#include "control/writing_task.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "signal/multisine.h"
#include "test_util.h"
#include "control/turntable.h"

namespace twinsim {
namespace {

using testing::SourcePath;

using testing::Turntable;
constexpr double kIlcJ = testing::kTurntableInertia;  // kg m^2

ArmReference Hold(double q, int samples, double ts) {
  ArmReference r;
  r.sample_time = ts;
  r.t = Eigen::VectorXd::LinSpaced(samples, 0, ts * (samples - 1));
  r.q = Eigen::MatrixXd::Constant(samples, 1, q);
  r.qd.setZero(samples, 1), r.qdd.setZero(samples, 1);
  return r;
}

TrackingOptions IlcPd() { return testing::TurntablePd(); }

// The exact sampled-data PS of the turntable: the torque is held over each sample
// (RK4 on a constant inertia is exact), so q(z) = G(z) u(z), qd(z) = Gv(z) u(z) with
// G = Ts^2 (z + 1) / (2 J (z - 1)^2), Gv = Ts / (J (z - 1)); the controller sends
// u = f - Kp q - Kd qd, which acts D samples later:
//   PS(z) = z^-D G / (1 + z^-D (Kp G + Kd Gv)).
std::complex<double> TurntablePs(double f, double ts, double kp, double kd, int delay) {
  const std::complex<double> z = std::polar(1.0, 2 * kPi * f * ts);
  const std::complex<double> g = ts * ts * (z + 1.0) / (2 * kIlcJ * (z - 1.0) * (z - 1.0));
  const std::complex<double> gv = ts / (kIlcJ * (z - 1.0));
  const std::complex<double> zd = std::pow(z, -delay);
  return zd * g / (1.0 + zd * (kp * g + kd * gv));
}

TEST(IlcFeedforward, ConstantTorqueOffsetsThePdLoopByFOverKp) {
  const ArmModel arm = Turntable();
  ASSERT_NEAR(MassMatrix(arm, Eigen::VectorXd::Zero(1))(0, 0), kIlcJ, 1e-12);
  const int samples = 2000;
  const ArmReference hold = Hold(0.2, samples, arm.sample_time);
  Eigen::MatrixXd f = Eigen::MatrixXd::Constant(samples, 1, 1.5);  // N·m
  TrackingOptions o = IlcPd();
  o.feedforward = &f;
  const TrackingTrial trial = RunTrackingTrial(arm, arm, hold, o);
  const double kp = PdFeedforwardGains(arm, Eigen::VectorXd::Constant(1, 0.2), 10, 1).kp[0];
  // Critically damped at 10 Hz: settled to 1e-6 after 2 s.
  EXPECT_NEAR(trial.q(samples - 1, 0) - 0.2, 1.5 / kp, 1e-6);
  EXPECT_NEAR(trial.demand(samples - 1, 0), 0, 1e-6);  // the feedback cancels f
  // Nothing moves before the delay has passed.
  EXPECT_EQ(trial.q(1, 0), 0.2);
  EXPECT_GT(trial.q(2, 0), 0.2);

  Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(samples - 1, 1);
  o.feedforward = &wrong;
  EXPECT_THROW(RunTrackingTrial(arm, arm, hold, o), std::invalid_argument);
}

TEST(IlcFrf, TurntableProcessSensitivityMatchesTheSampledClosedForm) {
  const ArmModel arm = Turntable();
  FrfOptions fo;
  fo.period = 0.5, fo.periods = 2, fo.f_min = 2, fo.f_max = 300;
  const ClosedLoopFrf frf = MeasureProcessSensitivity(arm, arm, {Eigen::VectorXd::Constant(1, 0.3)}, IlcPd(), fo);
  ASSERT_EQ(frf.response.size(), 1u);
  ASSERT_EQ(frf.frequency.size(), 150);
  const TrackingGains g = PdFeedforwardGains(arm, Eigen::VectorXd::Constant(1, 0.3), 10, 1);
  double worst = 0;
  for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
    const std::complex<double> want = TurntablePs(frf.frequency[i], arm.sample_time, g.kp[0], g.kd[0], 1);
    worst = std::max(worst, std::abs(frf.response[0][0][i] / want - 1.0));
  }
  // Linear, periodic and noise-free: the measurement is the closed form to 1e-6.
  EXPECT_LT(worst, 1e-6);
  // Continuous-time sanity: at 2 Hz |PS| is near 1/Kp.
  EXPECT_NEAR(std::abs(frf.response[0][0][0]) * g.kp[0], 1.0, 0.2);
}

TEST(IlcLearningFilter, FitInvertsTheTurntablesProcessSensitivityAndAgreesWithTheModel) {
  const ArmModel arm = Turntable();
  FrfOptions fo;
  fo.period = 0.5, fo.periods = 1, fo.f_min = 2, fo.f_max = 200;
  const ClosedLoopFrf frf = MeasureProcessSensitivity(arm, arm, {Eigen::VectorXd::Constant(1, 0.0)}, IlcPd(), fo);
  const LearningFilter l = FitLearningFilter(frf, 0, 2, 100, 4);
  EXPECT_EQ(l.shift, 1);                 // the command delay
  EXPECT_NEAR(l.inertia + l.inertia_early, kIlcJ, 0.05 * kIlcJ);  // it trades a little inertia for the hold's gain
  const LearningFilter m = ModelLearningFilter(arm, IlcPd(), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), 0);
  EXPECT_EQ(m.shift, 1);
  EXPECT_NEAR(m.inertia + m.inertia_early, kIlcJ, 1e-12);
  EXPECT_NEAR(l.stiffness, m.stiffness, 0.05 * m.stiffness);
  // PS L = 1 within 5 % up to 50 Hz and 15 % up to 100 Hz (a half-sample hold phase remains).
  for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
    const double err = std::abs(frf.response[0][0][i] * l.Response(frf.frequency[i], arm.sample_time) - 1.0);
    if (frf.frequency[i] <= 50) {
      EXPECT_LT(err, 0.05) << frf.frequency[i] << " Hz";
      // The a-priori filter of the exact model: the (1 + z) / 2 half-sample is second order.
      EXPECT_LT(std::abs(frf.response[0][0][i] * m.Response(frf.frequency[i], arm.sample_time) - 1.0), 0.05);
    }
    if (frf.frequency[i] <= 100) {
      EXPECT_LT(err, 0.15) << frf.frequency[i] << " Hz";
    }
  }
  EXPECT_LT(l.residual, 0.1);
}

TEST(IlcLearningFilter, ApplyIsTheFilterResponseOnASinusoid) {
  LearningFilter l;
  l.shift = 2, l.inertia = 0.3, l.inertia_early = 0.1, l.damping = 20, l.stiffness = 500;
  l.snap = 2e-6;  // the order-4 term: at 25 Hz, 2e-6 (2 pi 25)^4 = 0.77 N m/rad against 0.4 (2 pi 25)^2 = 9.9
  const double ts = 0.001, f = 25;  // an integer number of periods in 400 samples
  Eigen::VectorXd e(400);
  for (int k = 0; k < 400; ++k) e[k] = std::sin(2 * kPi * f * k * ts);
  const Eigen::VectorXd y = l.Apply(e, ts);
  const std::complex<double> h = l.Response(f, ts);
  for (int k = 10; k < 390; ++k) {
    EXPECT_NEAR(y[k], std::abs(h) * std::sin(2 * kPi * f * k * ts + std::arg(h)), 1e-6 * std::abs(h));
  }
}

// The letter T on `plant` under PD + feedforward with the bare arm's model: the PS
// measured at the first and last posture (2 periods), the learning filters, and the ILC.
struct Learning {
  ClosedLoopFrf frf;
  std::vector<LearningFilter> filters;
  IlcResult result;
};

Learning LearnT(const std::string& plant_file, const std::string& filter, const IlcOptions& options) {
  const ArmModel plant = LoadArmModel(SourcePath(plant_file));
  const ArmModel hat = LoadArmModel(SourcePath("models/rrr.yaml"));
  WritingTaskOptions w;
  w.letters = "T";
  const ArmReference ref = WritingTaskReference(hat, w);
  TrackingOptions t;
  t.controller = TrackingController::kPdFeedforward;
  FrfOptions fo;
  fo.periods = 2, fo.amplitude = 0.3;
  Learning out;
  out.frf = MeasureProcessSensitivity(plant, hat, {ref.q.row(0).transpose(), ref.q.row(ref.q.rows() - 1).transpose()},
                                      t, fo);
  for (int j = 0; j < 3; ++j) {
    out.filters.push_back(filter == "model" ? ModelLearningFilter(hat, t, ref.q.row(0).transpose(), ref.q.row(0).transpose(), j)
                                            : FitLearningFilter(out.frf, j, 2, 80, 5));
  }
  out.result = RunIlc(plant, hat, ref, t, out.filters, options);
  return out;
}

// The first trial whose worst RMS error is at least `factor` below trial 0's (-1: none).
int TrialReaching(const IlcResult& r, double factor) {
  for (int k = 0; k < static_cast<int>(r.error_rms.size()); ++k) {
    if (r.WorstRms(0) / r.WorstRms(k) >= factor) return k;
  }
  return -1;
}

TEST(IlcLearning, FittedFilterCutsTheLetterTsErrorTenfoldWithinTenTrials) {
  IlcOptions o;
  o.trials = 10, o.gain = 0.5, o.q_order = 4, o.q_cutoff = 40;
  const Learning l = LearnT("models/rrr_plant.yaml", "fitted", o);
  const IlcResult& r = l.result;
  ASSERT_EQ(r.error_rms.size(), 11u);
  // The plant carries a 0.5 kg payload at the tool: the elbow's fitted inertia is the
  // bare forearm's (0.045 kg m^2 at these postures) plus 0.5 * 0.35^2, within 15 %.
  const double elbow = l.filters[2].inertia + l.filters[2].inertia_early;
  EXPECT_NEAR(elbow, 0.045 + 0.5 * 0.35 * 0.35, 0.15 * 0.106);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(ConvergenceFactor(l.frf, j, l.filters[j], o).maxCoeff(), 1.0) << "joint " << j + 1;
  }
  const int reached = TrialReaching(r, 10);
  EXPECT_GE(reached, 1);
  EXPECT_LE(reached, 9) << r.FullReport();
  EXPECT_GE(r.Reduction(), 50) << r.FullReport();
  // Monotonic until tenfold (each trial at least 30 % better than the one before); then,
  // near the floor of a few 1e-5 rad, nearly so (never 25 % worse than the one before).
  for (int k = 1; k <= 10; ++k) {
    EXPECT_LT(r.WorstRms(k), (k <= reached ? 0.7 : 1.25) * r.WorstRms(k - 1)) << "trial " << k;
  }
  EXPECT_FALSE(r.Diverged());
}

TEST(IlcLearning, ModelFilterAtFullGainAndDeterminism) {
  IlcOptions o;
  o.trials = 6, o.gain = 1;
  const Learning a = LearnT("models/rrr_plant.yaml", "model", o);
  EXPECT_GE(a.result.Reduction(), 8) << a.result.FullReport();
  const Learning b = LearnT("models/rrr_plant.yaml", "model", o);
  ASSERT_EQ(a.result.error_rms.size(), b.result.error_rms.size());
  for (std::size_t k = 0; k < a.result.error_rms.size(); ++k) {
    EXPECT_EQ(a.result.error_rms[k], b.result.error_rms[k]);  // bit for bit
  }
  EXPECT_EQ(a.result.feedforward, b.result.feedforward);
}

// A flexible elbow drive (a resonance near 118 Hz the rigid filter does not know):
// without Q the learning feeds the resonance and diverges; with Q at 40 Hz it converges.
TEST(IlcLearning, RobustnessFilterKeepsAFlexibleElbowConverging) {
  IlcOptions o;
  o.trials = 5, o.gain = 0.5, o.q_order = 0;
  const Learning without = LearnT("models/rrr_plant_flex.yaml", "fitted", o);
  EXPECT_TRUE(without.result.Diverged()) << without.result.FullReport();
  EXPECT_GT(LearningLimitFrequency(without.frf, 2, without.filters[2], o.gain), 10);
  EXPECT_LT(LearningLimitFrequency(without.frf, 2, without.filters[2], o.gain), 60);
  o.q_order = 4, o.q_cutoff = 40;
  const Learning with = LearnT("models/rrr_plant_flex.yaml", "fitted", o);
  EXPECT_FALSE(with.result.Diverged());
  for (int k = 1; k <= 5; ++k) EXPECT_LT(with.result.WorstRms(k), with.result.WorstRms(k - 1)) << "trial " << k;
  EXPECT_GE(with.result.Reduction(), 1.5) << with.result.FullReport();
}

}  // namespace
}  // namespace twinsim
