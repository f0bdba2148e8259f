// Batch-adaptive estimation on a simulated plant whose parameters differ from the
// nominal model's (tests/identification/rrr_plant.yaml): the fixed point is the
// plant's truth, convergence within 8 trials, recovery of all 21 base parameters,
// tracking that improves, and the trial simulator's own behaviour.
#include "identification/batch_adaptive.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#include "identification/excitation_design.h"
#include "io/csv_table.h"
#include "test_util.h"

namespace twinsim {
namespace {

const ArmModel& Nominal() {
  static const ArmModel model = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  return model;
}

const ArmModel& Plant() {
  static const ArmModel plant = LoadArmModel(testing::SourcePath("tests/identification/rrr_plant.yaml"));
  return plant;
}

// One optimised excitation for all tests (5 harmonics of 0.1 Hz, a quick design).
const FourierTrajectory& Excitation() {
  static const FourierTrajectory t = [] {
    ExcitationOptions o;
    o.samples_per_period = 100;
    o.starts = 2;
    o.max_iterations = 40;
    o.penalty_rounds = 3;
    return DesignExcitation(Nominal(), o);
  }();
  return t;
}

Eigen::VectorXd TruePlantParameters(const BatchAdaptiveResult& r) {
  return r.base.from_standard * StandardParameters(Plant());
}

// Each base parameter's error relative to its own value; a parameter whose typical
// torque contribution (|beta_j| times its column's RMS over states within the limits,
// ExcitationColumnScales) is below 5 % of the largest one is judged relative to that
// 5 % level instead (the products of inertia here cause 0.04 .. 0.4 % of the largest
// torque).
double WorstError(const BatchAdaptiveResult& r, std::string* which) {
  const Eigen::VectorXd truth = TruePlantParameters(r);
  const Eigen::VectorXd scales =
      ExcitationColumnScales(Nominal(), r.base, ResolveExcitationLimits(Nominal(), ExcitationOptions{}));
  const double floor = 0.05 * scales.cwiseProduct(truth).cwiseAbs().maxCoeff();
  double worst = 0;
  for (int c = 0; c < truth.size(); ++c) {
    const double e = scales[c] * std::abs(r.beta[c] - truth[c]) / std::max(scales[c] * std::abs(truth[c]), floor);
    if (e > worst) {
      worst = e;
      *which = r.short_names[static_cast<std::size_t>(c)];
    }
  }
  return worst;
}

ArmTrialOptions NoisyPlant() {
  ArmTrialOptions plant;
  plant.encoder_resolution = 2 * kPi / 65536;            // 16 bit per turn
  plant.torque_noise = Eigen::VectorXd::Constant(3, 0.1);  // N·m
  plant.seed = 7;
  return plant;
}

TEST(BatchAdaptive, ThePlantsTrueParametersAreTheFixedPoint) {
  BatchAdaptiveOptions o;
  o.max_trials = 1;
  o.initial = FindBaseParameters(Nominal()).from_standard * StandardParameters(Plant());
  const BatchAdaptiveResult r = RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), {}));
  ASSERT_EQ(r.trials.size(), 1u);
  // With the true parameters the feedforward alone tracks: the feedback is left with
  // the stick-slip near standstill, and the update moves the feedforward by < 1e-4.
  EXPECT_LT(r.trials[0].relative_change, 1e-4);
  EXPECT_LT(r.trials[0].error_rms.maxCoeff(), 2e-5);  // rad
}

TEST(BatchAdaptive, ConvergesToThePlantWithoutNoise) {
  BatchAdaptiveOptions o;
  o.tolerance = 1e-5;
  const BatchAdaptiveResult r = RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), {}));
  ASSERT_TRUE(r.converged) << r.FullReport();
  EXPECT_LE(r.trials.size(), 8u) << r.FullReport();
  // The nominal model starts several % off the plant.
  EXPECT_GT(r.trials.front().relative_change, 0.03);
  // All 21 base parameters within 1 % (measured: 0.06 %; relative to their own values,
  // even the smallest products of inertia are within 0.9 %).
  ASSERT_EQ(r.beta.size(), 21);
  std::string which;
  EXPECT_LT(WorstError(r, &which), 0.01) << which << "\n" << r.FullReport();
  // Tracking improves at least 10 times on every joint, and never gets worse.
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(r.trials.back().error_rms[i] * 10, r.trials.front().error_rms[i]) << "joint " << i + 1;
    for (std::size_t k = 1; k < r.trials.size(); ++k)
      EXPECT_LE(r.trials[k].error_rms[i], r.trials[k - 1].error_rms[i] * 1.05) << "joint " << i + 1 << " trial " << k;
  }
}

TEST(BatchAdaptive, ConvergesWithQuantisationAndTorqueNoise) {
  BatchAdaptiveOptions o;
  o.tolerance = 2e-3;  // above the trial-to-trial scatter the noise causes (about 1e-3)
  const BatchAdaptiveResult r = RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), NoisyPlant()));
  ASSERT_TRUE(r.converged) << r.FullReport();
  EXPECT_LE(r.trials.size(), 8u);
  // Within 5 % (measured: 0.6 .. 1.4 % over noise seeds 1 to 8).
  std::string which;
  EXPECT_LT(WorstError(r, &which), 0.05) << which << "\n" << r.FullReport();
  for (int i = 0; i < 3; ++i) EXPECT_LT(r.trials.back().error_rms[i] * 3, r.trials.front().error_rms[i]);
}

TEST(BatchAdaptive, OptimisedExcitationRecoversBetterThanARandomOne) {
  // The same noise along a random feasible excitation (condition number 141 against
  // 3.9): the parameters it hardly excites come out far worse.
  BatchAdaptiveOptions o;
  o.tolerance = 2e-3;
  o.max_trials = 4;
  const FourierTrajectory random = RandomFeasibleExcitation(Nominal(), ExcitationOptions{}, 1000003);
  const BatchAdaptiveResult r = RunBatchAdaptive(Nominal(), random, o, SimulatedTrials(Plant(), NoisyPlant()));
  const BatchAdaptiveResult d = RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), NoisyPlant()));
  std::string which;
  const double optimised = WorstError(d, &which), baseline = WorstError(r, &which);
  // Measured: 1.0 % against 19 %.
  EXPECT_LT(optimised * 10, baseline) << which;
}

TEST(BatchAdaptive, TrialsAreSeededAndQuantised) {
  const FourierTrajectory& t = Excitation();
  ArmTrialInput in;
  in.sample_time = 0.001;
  const SampledMotion s = SampleFourier(t, 0.001, 0.5);
  in.q_ref = s.q;
  in.qd_ref = s.qd;
  in.feedforward = Eigen::MatrixXd::Zero(s.q.rows(), 3);
  in.hold_command = Eigen::VectorXd::Zero(3);
  in.kp = Eigen::VectorXd::Constant(3, 500);
  in.kd = Eigen::VectorXd::Constant(3, 10);
  ArmTrialOptions o;
  o.encoder_resolution = 1e-3;
  o.torque_noise = Eigen::VectorXd::Constant(3, 0.5);
  const ArmTrial a = RunTrial(Plant(), in, o, 1), b = RunTrial(Plant(), in, o, 1), c = RunTrial(Plant(), in, o, 2);
  EXPECT_EQ(a.q_measured, b.q_measured);
  EXPECT_EQ(a.feedback, b.feedback);
  EXPECT_NE(a.feedback, c.feedback);
  for (Eigen::Index k = 0; k < a.q_measured.size(); ++k) {
    const double counts = a.q_measured.data()[k] / 1e-3;
    EXPECT_NEAR(counts, std::round(counts), 1e-9);
  }
  // PD only, the arm sags under gravity: the shoulder's error is what Kp needs to hold it.
  EXPECT_GT(a.q_measured.col(1).minCoeff(), in.q_ref.col(1).minCoeff() - 0.1);
  in.kp.resize(2);
  EXPECT_THROW(RunTrial(Plant(), in, o), std::invalid_argument);  // our own bug, not the user's
  in.kp = Eigen::VectorXd::Constant(3, 500);
  o.torque_noise = Eigen::VectorXd::Constant(2, 0.5);
  EXPECT_THROW(RunTrial(Plant(), in, o), InputError);
}

TEST(BatchAdaptive, CsvHasOneRowPerTrial) {
  BatchAdaptiveOptions o;
  o.max_trials = 2;
  const BatchAdaptiveResult r = RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), {}));
  const CsvTable csv = ParseCsvTable(FormatBatchAdaptiveCsv(r), "adaptive.csv");
  ASSERT_EQ(csv.rows.size(), 2u);
  ASSERT_EQ(csv.header.size(), 1u + 21u + 9u + 1u);
  EXPECT_EQ(csv.header[0], "trial");
  EXPECT_EQ(csv.header[22], "rms1");
  EXPECT_EQ(csv.header.back(), "change");
  EXPECT_NEAR(csv.rows[1][csv.RequireColumn("rms2")], r.trials[1].error_rms[1], 1e-9);
  EXPECT_NEAR(csv.rows[1][csv.RequireColumn("change")], r.trials[1].relative_change, 1e-6 * r.trials[1].relative_change);
}

TEST(BatchAdaptive, OptionsAreChecked) {
  std::string error;
  BatchAdaptiveOptions o;
  EXPECT_TRUE(o.IsValid(&error));
  o.learning_gain = 2;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "learning gain must be in (0, 2)");
  o = BatchAdaptiveOptions{};
  o.kp = Eigen::VectorXd::Constant(3, 100);
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "kp and kd must both be given or both be empty");
  o.kd = Eigen::VectorXd::Constant(2, 1);
  o.kp = Eigen::VectorXd::Constant(2, 100);
  try {
    RunBatchAdaptive(Nominal(), Excitation(), o, SimulatedTrials(Plant(), {}));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "batch-adaptive options: kp and kd need 3 values");
  }
}

}  // namespace
}  // namespace twinsim
