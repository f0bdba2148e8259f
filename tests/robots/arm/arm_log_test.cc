// The contract's arm log: reading, checks with file:line:column, derived derivatives.
#include "robots/arm/arm_log.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::string ArmLogErrorOf(const std::string& text, const ArmLogOptions& options = {}) {
  try {
    ParseArmLog(text, "arm.csv", options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Two joints at 100 Hz: q1 = sin(2 pi 0.5 t), q2 = 0.2 t^2 (extra columns in between).
std::string TwoJointLog(int rows, bool derivatives) {
  std::string s = derivatives ? "t,q1,q2,extra,qd1,qd2,qdd1,qdd2,tau1,tau2\n" : "t,q1,q2,extra,tau1,tau2\n";
  for (int r = 0; r < rows; ++r) {
    const double t = r * 0.01, w = 2 * kPi * 0.5;
    char line[256];
    if (derivatives) {
      std::snprintf(line, sizeof line, "%.4f,%.12f,%.12f,7,%.12f,%.12f,%.12f,%.12f,%.6f,%.6f\n", t, std::sin(w * t),
                    0.2 * t * t, w * std::cos(w * t), 0.4 * t, -w * w * std::sin(w * t), 0.4, 1.0 + t, -2.0);
    } else {
      std::snprintf(line, sizeof line, "%.4f,%.12f,%.12f,7,%.6f,%.6f\n", t, std::sin(w * t), 0.2 * t * t, 1.0 + t, -2.0);
    }
    s += line;
  }
  return s;
}

TEST(ArmLog, ReadsJointColumnsAndIgnoresExtraOnes) {
  const ArmLog log = ParseArmLog(TwoJointLog(300, true), "arm.csv");
  EXPECT_EQ(log.dof, 2);
  EXPECT_EQ(log.rows(), 300);
  EXPECT_TRUE(log.qd_logged);
  EXPECT_TRUE(log.qdd_logged);
  EXPECT_EQ(log.derive_cutoff_hz, 0);
  EXPECT_NEAR(log.sample_period, 0.01, 1e-12);
  EXPECT_NEAR(log.qd(100, 1), 0.4, 1e-12);
  EXPECT_NEAR(log.tau(3, 0), 1.03, 1e-12);
  EXPECT_EQ(log.qref.size(), 0);
  EXPECT_EQ(log.line_of[0], 2);
  const ArmLog with_reference = ParseArmLog("t,q1,tau1,qref1\n0,0,1,0.5\n0.01,0,1,0.25\n0.02,0,1,0\n", "ref.csv");
  ASSERT_EQ(with_reference.qref.rows(), 3);
  EXPECT_EQ(with_reference.qref(1, 0), 0.25);
  EXPECT_EQ(FormatArmLog(with_reference, false).substr(0, 16), "t,q1,tau1,qref1\n");
  // Extra columns, numeric or not, are ignored (CONTRACT.md).
  const ArmLog with_text = ParseArmLog("t,q1,tau1,arm,note\n0,0,1,kuka,\n0.01,0,1,kuka,nan\n0.02,0,2,kuka,x\n", "text.csv");
  EXPECT_EQ(with_text.tau(2, 0), 2);
}

TEST(ArmLog, DerivesVelocityAndAccelerationFromPositions) {
  // 100 Hz, default cut-off 10 Hz (lowered to a quarter of the rate: 25 Hz is above it).
  const ArmLog log = ParseArmLog(TwoJointLog(500, false), "arm.csv");
  EXPECT_FALSE(log.qd_logged);
  EXPECT_EQ(log.derive_cutoff_hz, 10);
  EXPECT_EQ(log.edge_samples, 40);  // four periods of the cut-off
  const double w = 2 * kPi * 0.5;
  double worst_qd = 0, worst_qdd = 0;
  for (int r = log.edge_samples; r < log.rows() - log.edge_samples; ++r) {
    const double t = log.t[r];
    worst_qd = std::max(worst_qd, std::abs(log.qd(r, 0) - w * std::cos(w * t)) / w);
    worst_qdd = std::max(worst_qdd, std::abs(log.qdd(r, 0) + w * w * std::sin(w * t)) / (w * w));
    worst_qd = std::max(worst_qd, std::abs(log.qd(r, 1) - 0.4 * t));
    worst_qdd = std::max(worst_qdd, std::abs(log.qdd(r, 1) - 0.4) / 0.4);
  }
  // Rounding to 12 decimals and the differences' (w h)^2 / 6 = 1.6e-4 relative error.
  EXPECT_LT(worst_qd, 3e-4);
  EXPECT_LT(worst_qdd, 3e-4);
  // A low sample rate lowers the cut-off to a quarter of it.
  ArmLogOptions options;
  options.cutoff_hz = 40;
  EXPECT_NEAR(ParseArmLog(TwoJointLog(100, false), "arm.csv", options).derive_cutoff_hz, 25, 1e-9);
}

TEST(ArmLog, RoundTripsThroughItsCsv) {
  const ArmLog log = ParseArmLog(TwoJointLog(50, true), "arm.csv");
  const std::string text = FormatArmLog(log, true);
  EXPECT_EQ(text.substr(0, text.find('\n')), "t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2");
  const ArmLog back = ParseArmLog(text, "again.csv");
  EXPECT_LT((back.q - log.q).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((back.qdd - log.qdd).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(FormatArmLog(back, true), text);
  const std::string dir = testing::TempDir("arm_log");
  WriteArmLog(dir + "/log.csv", log, false);
  EXPECT_EQ(ReadArmLog(dir + "/log.csv").q.rows(), 50);
  WriteArmTorqueCsv(dir + "/tau.csv", log.t.head(2), log.tau.topRows(2));
  EXPECT_EQ(testing::ReadText(dir + "/tau.csv"), "t,tau1,tau2\n0,1,-2\n0.01,1.01,-2\n");
}

TEST(ArmLog, BadInputNamesFileLineAndColumn) {
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau1\n0,0,0\n0.01,x,0\n0.02,0,0\n"), "arm.csv:3:6: column 'q1': expected a number, got 'x'");
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau1\n0,0,0\n0.01,0,0\n0.01,0,0\n"),
            "arm.csv:4:1: column 't': time goes backwards or stands still: t = 0.01 after 0.01");
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau1\n0,0,0\n0.01,0,0\n0.02,0,0\n0.03,0,0\n0.05,0,0\n0.06,0,0\n"),
            "arm.csv:6:1: column 't': irregular sampling: 0.02 s after the previous row, but the median step is 0.01 s "
            "(an arm log must be nearly uniform: every step within 50 % of the median)");
  EXPECT_EQ(ArmLogErrorOf("t,q1,q2,tau1\n0,0,0,0\n"), "arm.csv:1: the log has q1..q2 but tau1: every joint needs a position and a torque column");
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau2,tau1\n0,0,0,0\n"),
            "arm.csv:1: the log has q1 but tau1..tau2: every joint needs a position and a torque column");
  EXPECT_EQ(ArmLogErrorOf("t,q1,q2,tau1,tau2,qd1\n0,0,0,0,0,0\n"), "arm.csv:1: the log has q1..q2 but qd1: give qd1..qd2 or none of them");
  EXPECT_EQ(ArmLogErrorOf("t,q1,q3,tau1,tau3\n0,0,0,0,0\n"),
            "arm.csv:1: missing column 'q2': joint columns must run q1..q3 without gaps");
  EXPECT_EQ(ArmLogErrorOf("t,tau1\n0,0\n").rfind("arm.csv:1: missing column 'q1' (have: t, tau1)", 0), 0u);
  EXPECT_EQ(ArmLogErrorOf("q1,tau1\n0,0\n").rfind("arm.csv:1: missing column 't'", 0), 0u);
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau1\n0,0,0\n0.01,0,0\n"), "arm.csv:2: an arm log needs at least 3 rows, got 2");
  ArmLogOptions bad;
  bad.cutoff_hz = -1;
  EXPECT_EQ(ArmLogErrorOf("t,q1,tau1\n0,0,0\n0.01,0,0\n0.02,0,0\n", bad),
            "the cut-off for derived velocities must be positive and at most 1e6 Hz, got -1 Hz");
  try {
    ReadArmLog("/nonexistent/arm.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/arm.csv: cannot open file");
  }
}

TEST(ArmLog, JointCountMustMatchTheModel) {
  const ArmLog log = ParseArmLog(TwoJointLog(10, true), "two.csv");
  ArmModel model = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  try {
    CheckArmLogMatchesModel(log, model);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "two.csv:1: the log has 2 joints (q1..q2, tau1..tau2) but the model 'rrr' (" +
                                         testing::SourcePath("models/rrr.yaml") + ") has 3");
  }
  model.joints.pop_back();
  EXPECT_NO_THROW(CheckArmLogMatchesModel(log, model));
}

}  // namespace
}  // namespace twinsim
