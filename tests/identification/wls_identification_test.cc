// Identification recovers known parameters from synthetic measurements, refuses data
// that does not excite a parameter, and always returns a physically consistent model.
#include "identification/wls_identification.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "analysis/arm_replay.h"
#include "core/error.h"
#include "identification/synthetic_arm_data.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::MakeMultiSine;
using testing::MakeSyntheticLog;
using testing::SensorNoise;

ArmModel WlsRrr() { return LoadArmModel(testing::SourcePath("models/rrr.yaml")); }

// The "true" arm: models/rrr.yaml with every mass, centre of mass, inertia and friction
// changed by up to +-20 %, the centres of mass moved off the links' axes and the
// inertias turned (products of inertia), so that no base parameter is zero.
ArmModel TrueRrr() {
  ArmModel m = WlsRrr();
  const double mass[] = {1.2, 0.85, 1.15};
  const Eigen::Vector3d com_shift[] = {{0.02, 0.03, -0.015}, {0.03, -0.02, 0.015}, {-0.025, 0.02, -0.01}};
  const Eigen::Vector3d inertia_scale[] = {{1.2, 0.8, 1.1}, {0.85, 1.2, 1.15}, {1.2, 1.05, 0.95}};
  const double viscous[] = {1.2, 0.8, 1.2}, coulomb[] = {0.8, 1.2, 0.85};
  for (int i = 0; i < 3; ++i) {
    ArmJoint& j = m.joints[static_cast<std::size_t>(i)];
    j.child.mass *= mass[i];
    j.child.com = 1.1 * j.child.com + com_shift[i];
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(0.3 + 0.2 * i, Eigen::Vector3d(1, -2, 1 + i).normalized()).toRotationMatrix();
    j.child.inertia = turn * (inertia_scale[i].asDiagonal() * j.child.inertia) * turn.transpose();
    j.viscous *= viscous[i];
    j.coulomb *= coulomb[i];
  }
  EXPECT_EQ(m.Validate(), "");
  return m;
}

// A log as a file would give it: written as CSV with t, q and tau only, then read back,
// so that qd and qdd are derived from q by the reader.
ArmLog ThroughCsv(const ArmLog& log) { return ParseArmLog(FormatArmLog(log, false), "synthetic.csv"); }

// Checks every base parameter against the truth; returns the worst relative error.
double WorstRelativeError(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth,
                          const std::vector<std::string>& names, double tolerance) {
  double worst = 0;
  for (Eigen::Index k = 0; k < truth.size(); ++k) {
    const double relative = std::abs(estimate[k] - truth[k]) / std::abs(truth[k]);
    worst = std::max(worst, relative);
    EXPECT_LE(relative, tolerance) << names[static_cast<std::size_t>(k)] << ": true " << truth[k] << ", identified "
                                   << estimate[k];
  }
  return worst;
}

TEST(WlsIdentification, RecoversEveryBaseParameterWithin1PercentWithoutNoise) {
  const ArmModel truth = TrueRrr();
  const ArmModel a_priori = WlsRrr();
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 11), 20.0, 1000.0, SensorNoise{}));
  ASSERT_FALSE(log.qd_logged);
  WlsIdentificationOptions options;
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(a_priori, {log}, options, &summary);

  // The test, not the code under test, knows the truth.
  const BaseParameters base = IdentificationBase(a_priori, options);
  const Eigen::VectorXd beta_true = base.from_standard * StandardParameters(truth);
  ASSERT_EQ(base.rank(), 21);  // 15 inertial + 6 friction
  for (int k = 0; k < 21; ++k) EXPECT_GT(std::abs(beta_true[k]), 1e-4) << base.names[static_cast<std::size_t>(k)];
  const double worst = WorstRelativeError(summary.identified, beta_true, base.names, 0.01);
  // The model written back has the same base parameters and passes validation. (The
  // minimum-norm correction of rrr.yaml's symmetric links gives an upper arm and a
  // forearm that break the triangle inequality; the consistent fit keeps beta.)
  EXPECT_EQ(identified.Validate(), "");
  WorstRelativeError(base.from_standard * StandardParameters(identified), beta_true, base.names, 0.01);
  // The a-priori model is far off; the identified one explains the torques.
  for (int j = 0; j < 3; ++j) {
    EXPECT_GT(summary.error_rms_a_priori[j], 0.02 * summary.torque_rms[j]) << j;
    EXPECT_LT(summary.error_rms_model[j], 0.002 * summary.torque_rms[j]) << j;
  }
  EXPECT_LT(summary.condition_number, 1e3);
  std::printf("noise-free: worst relative error %.3g %%, condition number %.1f\n", 100 * worst,
              summary.condition_number);
}

TEST(WlsIdentification, RecoversEveryBaseParameterWithin5PercentFromQuantisedPositionsAndNoisyTorques) {
  const ArmModel truth = TrueRrr();
  const ArmModel a_priori = WlsRrr();
  SensorNoise noise;
  noise.counts_per_rev = 1 << 18;  // 24 micro-rad steps
  noise.torque_fraction = 0.02;    // 2 % of each joint's torque RMS
  noise.seed = 3;
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 11), 20.0, 1000.0, noise));
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(a_priori, {log}, {}, &summary);
  const BaseParameters base = IdentificationBase(a_priori, {});
  const Eigen::VectorXd beta_true = base.from_standard * StandardParameters(truth);
  const double worst = WorstRelativeError(summary.identified, beta_true, base.names, 0.05);
  WorstRelativeError(base.from_standard * StandardParameters(identified), beta_true, base.names, 0.05);
  // The weights are the noise levels (2 % of the torque RMS), and the errors are within
  // three of the reported standard deviations.
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(summary.joint_sigma[j], 0.02 * summary.torque_rms[j], 0.004 * summary.torque_rms[j]) << j;
  for (int k = 0; k < 21; ++k) {
    const double sigma = summary.relative_std[k] / 100 * std::abs(summary.identified[k]);
    EXPECT_LT(std::abs(summary.identified[k] - beta_true[k]), 3 * sigma + 1e-9) << base.names[static_cast<std::size_t>(k)];
  }
  std::printf("noisy: worst relative error %.3g %%, largest relative std dev %.3g %%\n", 100 * worst,
              summary.relative_std.maxCoeff());
}

TEST(WlsIdentification, IsDeterministic) {
  const ArmModel truth = TrueRrr();
  SensorNoise noise;
  noise.counts_per_rev = 1 << 18;
  noise.torque_fraction = 0.02;
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 5), 6.0, 500.0, noise));
  WlsIdentificationSummary a, b;
  IdentifyArmByLeastSquares(WlsRrr(), {log}, {}, &a);
  IdentifyArmByLeastSquares(WlsRrr(), {log}, {}, &b);
  EXPECT_EQ(a.identified, b.identified);
  EXPECT_EQ(a.consistent, b.consistent);
}

TEST(WlsIdentification, AJointThatNeverMovesIsNamed) {
  const ArmModel truth = TrueRrr();
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 11), 10.0, 500.0, SensorNoise{}, 2));
  try {
    IdentifyArmByLeastSquares(WlsRrr(), {log}, {});
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("synthetic.csv: the data does not excite base parameters", 0), 0u) << what;
    EXPECT_NE(what.find("fv3 (viscous friction of joint 3: it never moves)"), std::string::npos) << what;
    EXPECT_NE(what.find("fc3 (Coulomb friction of joint 3: it never moves)"), std::string::npos) << what;
    EXPECT_NE(what.find("q3 spans only 0"), std::string::npos) << what;
  }
}

TEST(WlsIdentification, NegativeFrictionInTheDataIsClippedAndTheShiftReported) {
  // The "measured" arm has negative viscous friction on joint 2 (no real arm does): the
  // identified base parameter is negative, and the model written back must not be.
  ArmModel odd = TrueRrr();
  odd.joints[1].viscous = -0.2;
  const ArmLog log = ThroughCsv(MakeSyntheticLog(odd, MakeMultiSine(odd, 11), 10.0, 500.0, SensorNoise{}));
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(WlsRrr(), {log}, {}, &summary);
  const auto fv2 = std::find(summary.names.begin(), summary.names.end(), "fv2") - summary.names.begin();
  ASSERT_LT(fv2, static_cast<long>(summary.names.size()));
  EXPECT_NEAR(summary.identified[fv2], -0.2, 0.005);
  EXPECT_TRUE(summary.consistency_fixed);
  EXPECT_EQ(identified.Validate(), "");
  EXPECT_GE(identified.joints[1].viscous, 0.0);
  EXPECT_LT(identified.joints[1].viscous, 1e-3);
  EXPECT_GT(summary.consistency_shift_max_std, 10.0);
  bool noted = false;
  for (const auto& note : summary.consistency_notes) noted |= note.find("viscous friction must not be negative") != std::string::npos;
  EXPECT_TRUE(noted);
  EXPECT_NE(summary.FullReport().find("made consistent"), std::string::npos);
}

TEST(WlsIdentification, AnUnphysicalInertiaIsFixedInTheDirectionsTheTorquesDoNotSee) {
  // The forearm turns about its own z axis only, so the torques fix Izz3 and Iyy3 - Ixx3
  // but not Ixx3 + Iyy3. A-priori values far too small for the true Izz3 give a
  // minimum-norm forearm that breaks the triangle inequality; the fix raises Ixx3 + Iyy3
  // and leaves the base parameters, and so the torques, as identified.
  ArmModel a_priori = WlsRrr();
  a_priori.joints[2].child.inertia = Eigen::Vector3d(0.0002, 0.0016, 0.0016).asDiagonal();
  ASSERT_EQ(a_priori.Validate(), "");
  const ArmModel truth = TrueRrr();
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 11), 10.0, 500.0, SensorNoise{}));
  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArmByLeastSquares(a_priori, {log}, {}, &summary);
  EXPECT_TRUE(summary.consistency_fixed);
  ASSERT_FALSE(summary.consistency_notes.empty());
  EXPECT_NE(summary.consistency_notes[0].find("triangle inequality"), std::string::npos) << summary.consistency_notes[0];
  EXPECT_EQ(identified.Validate(), "");
  EXPECT_LT(summary.consistency_shift_max_std, 0.01);
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(summary.error_rms_model[j], summary.error_rms_identified[j], 1e-6 * summary.torque_rms[j]);
}

TEST(WlsIdentification, DecimationAndOptionsAreChecked) {
  WlsIdentificationOptions options;
  std::string why;
  options.decimate = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "decimate must be at least 1, got 0");
  options.decimate = 1;
  options.max_condition_number = 0.5;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_THROW(IdentifyArmByLeastSquares(WlsRrr(), {}, {}), InputError);

  // Every 4th sample of a 1 kHz log gives nearly the same answer.
  const ArmModel truth = TrueRrr();
  const ArmLog log = ThroughCsv(MakeSyntheticLog(truth, MakeMultiSine(truth, 11), 10.0, 1000.0, SensorNoise{}));
  WlsIdentificationSummary all, quarter;
  IdentifyArmByLeastSquares(WlsRrr(), {log}, {}, &all);
  WlsIdentificationOptions decimated;
  decimated.decimate = 4;
  IdentifyArmByLeastSquares(WlsRrr(), {log}, decimated, &quarter);
  EXPECT_NEAR(quarter.samples, all.samples / 4.0, 1.0);
  EXPECT_LT((quarter.identified - all.identified).cwiseQuotient(all.identified).cwiseAbs().maxCoeff(), 0.01);
}

TEST(WlsIdentification, DescribesParametersInWords) {
  const ArmModel m = WlsRrr();
  const BaseParameters base = IdentificationBase(m, {});
  bool friction = false;
  for (int k = 0; k < base.rank(); ++k) {
    if (base.names[static_cast<std::size_t>(k)] == "fc3") {
      EXPECT_EQ(DescribeBaseParameter(m, base, k), "Coulomb friction of joint 3");
      friction = true;
    }
    if (base.names[static_cast<std::size_t>(k)].rfind("Izz1 + ", 0) == 0) {
      EXPECT_EQ(DescribeBaseParameter(m, base, k).rfind("inertia Izz of link 1 about its frame's origin, regrouped with", 0),
                0u);
    }
  }
  EXPECT_TRUE(friction);
}

// A joint that moves, stops for a second and moves again, logged at 1 kHz as q alone: the
// dwell's rows are at rest, and so is every row within one cut-off period (0.1 s at
// 10 Hz) of them, where the derived q̇ still moves while the joint already sticks.
TEST(WlsIdentification, RowsAtRestAndWithinOneCutOffPeriodOfThemAreMarked) {
  std::string csv = "t,q1,tau1\n";
  double q = 0;
  for (int k = 0; k <= 3000; ++k) {
    if (k < 1000 || k >= 2000) q += 0.1e-3;  // 0.1 m/s, then still, then 0.1 m/s
    csv += std::to_string(k * 1e-3) + "," + std::to_string(q) + ",1\n";
  }
  ArmLogOptions options;
  options.cutoff_hz = 10;
  const ArmLog log = ParseArmLog(csv, "stop.csv", options);
  const Eigen::VectorXd speed = ArmRestSpeeds({log}, 0.02);
  EXPECT_NEAR(speed[0], 0.02 * 0.1 * std::sqrt(2.0 / 3), 2e-4);  // 2 % of the RMS speed
  const auto rest = ArmRestRows(log, speed);
  EXPECT_TRUE(rest(1500, 0));
  // The derived q̇ falls below 2 % about 30 ms inside the dwell (measured: rows 1029 and
  // 1969); the 0.1 s before and after are marked (929 to 2069), beyond 0.15 s nothing.
  EXPECT_TRUE(rest(1000 - 60, 0));
  EXPECT_TRUE(rest(2000 + 60, 0));
  EXPECT_FALSE(rest(1000 - 150, 0));
  EXPECT_FALSE(rest(2000 + 150, 0));
  EXPECT_FALSE(rest(500, 0));
  // A logged q̇ is not smeared: only its own rows below the speed.
  ArmLog logged = log;
  logged.qd_logged = true;
  logged.qd.col(0).setConstant(0.1);
  logged.qd.block(1000, 0, 1000, 1).setZero();
  const auto sharp = ArmRestRows(logged, speed);
  EXPECT_TRUE(sharp(1000, 0) && sharp(1999, 0));
  EXPECT_FALSE(sharp(999, 0) || sharp(2000, 0));

  WlsIdentificationOptions bad;
  bad.rest_share = 1;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("rest_share"), std::string::npos) << why;
  bad.rest_share = -0.1;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(WlsIdentification, AJointAtRestOnEveryRowIsNamed) {
  // Steps of 0.5 mm every 0.4 s: each 50 ms move lies within one period of the 10 Hz
  // cut-off of the rest before or after it.
  std::string csv = "t,q1,tau1\n";
  double q = 0;
  for (int k = 0; k <= 6000; ++k) {
    if (k % 400 < 50) q += 0.5e-3 / 50;
    csv += std::to_string(k * 1e-3) + "," + std::to_string(q) + "," + std::to_string(k % 400 < 50 ? 5 : 0) + "\n";
  }
  const ArmModel cart = LoadArmModelFromYamlString(R"(robot: arm
name: cart
gravity: [0, 0, -9.81]
joints:
  - {name: axis, type: prismatic, axis: [1, 0, 0], lower: -1, upper: 1,
     link: {name: cart, mass: 8, com: [0, 0, 0], inertia: [1, 1, 1, 0, 0, 0]}}
)",
                                                   "cart.yaml");
  try {
    IdentifyArmByLeastSquares(cart, {ParseArmLog(csv, "steps.csv")}, {});
    FAIL() << "identified a joint that never left rest";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 1 is at rest or near it on every one of the"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace twinsim
