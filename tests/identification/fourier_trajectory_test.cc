// The Fourier excitation trajectory: closed forms, derivatives against finite
// differences, periodicity, its file format and the reference log.
#include "identification/fourier_trajectory.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "io/csv_table.h"
#include "robots/arm/arm_dynamics.h"
#include "test_util.h"

namespace twinsim {
namespace {

FourierTrajectory RandomTrajectory(int n, int harmonics, double f, std::uint64_t seed) {
  Rng rng(seed);
  FourierTrajectory t = ZeroFourierTrajectory(n, harmonics, f);
  for (int i = 0; i < n; ++i) {
    t.q0[i] = rng.Uniform(-1, 1);
    for (int l = 0; l < harmonics; ++l) {
      t.a(i, l) = rng.Uniform(-1, 1);
      t.b(i, l) = rng.Uniform(-1, 1);
    }
  }
  return t;
}

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseFourierTrajectoryYaml(yaml, "exc.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FourierTrajectory, OneHarmonicMatchesTheClosedForm) {
  // a = 0.6, b = -0.3 on the second harmonic of 0.25 Hz: w2 = pi rad/s.
  FourierTrajectory t = ZeroFourierTrajectory(1, 2, 0.25);
  t.q0[0] = 0.2;
  t.a(0, 1) = 0.6;
  t.b(0, 1) = -0.3;
  const double w = kPi;
  for (double time : {0.0, 0.3, 1.7, 3.9}) {
    const JointMotion m = EvaluateFourier(t, time);
    EXPECT_NEAR(m.q[0], 0.2 + 0.6 / w * std::sin(w * time) + 0.3 / w * std::cos(w * time), 1e-15);
    EXPECT_NEAR(m.qd[0], 0.6 * std::cos(w * time) - 0.3 * std::sin(w * time), 1e-15);
    EXPECT_NEAR(m.qdd[0], -0.6 * w * std::sin(w * time) - 0.3 * w * std::cos(w * time), 1e-14);
  }
}

TEST(FourierTrajectory, DerivativesMatchFiniteDifferences) {
  const FourierTrajectory t = RandomTrajectory(3, 5, 0.1, 7);
  const double h = 1e-5;
  for (double time : {0.0, 1.234, 4.5, 9.99}) {
    const JointMotion m = EvaluateFourier(t, time);
    const JointMotion p = EvaluateFourier(t, time + h), n = EvaluateFourier(t, time - h);
    // Central differences: truncation error h^2/6 * |q'''| (about 1e-10 here).
    EXPECT_LT(((p.q - n.q) / (2 * h) - m.qd).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT(((p.qd - n.qd) / (2 * h) - m.qdd).cwiseAbs().maxCoeff(), 1e-8);
  }
}

TEST(FourierTrajectory, RepeatsEveryPeriod) {
  const FourierTrajectory t = RandomTrajectory(2, 4, 0.1, 3);
  ASSERT_DOUBLE_EQ(t.period(), 10.0);
  for (double time : {0.0, 0.5, 3.3, 7.25}) {
    const JointMotion a = EvaluateFourier(t, time), b = EvaluateFourier(t, time + t.period()),
                      c = EvaluateFourier(t, time + 3 * t.period());
    EXPECT_LT((a.q - b.q).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((a.qd - c.qd).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((a.qdd - c.qdd).cwiseAbs().maxCoeff(), 1e-11);
  }
  // The mean over a period is q0 and the mean velocity zero.
  const SampledMotion s = SampleFourier(t, 0.01, t.period());
  ASSERT_EQ(s.t.size(), 1000u);
  EXPECT_LT((s.q.colwise().mean().transpose() - t.q0).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(s.qd.colwise().mean().cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FourierTrajectory, FileRoundTripsExactly) {
  FourierTrajectory t = RandomTrajectory(3, 4, 0.1, 11);
  t.joint_names = {"waist", "shoulder", "elbow"};
  t.model = "rrr";
  const std::string dir = testing::TempDir("fourier_roundtrip");
  SaveFourierTrajectory(t, dir + "/exc.yaml");
  const FourierTrajectory u = LoadFourierTrajectory(dir + "/exc.yaml");
  EXPECT_EQ(u.fundamental, t.fundamental);
  EXPECT_EQ(u.q0, t.q0);
  EXPECT_EQ(u.a, t.a);
  EXPECT_EQ(u.b, t.b);
  EXPECT_EQ(u.joint_names, t.joint_names);
  EXPECT_EQ(u.model, "rrr");
  EXPECT_EQ(FormatFourierTrajectoryYaml(u), testing::ReadText(dir + "/exc.yaml"));
}

TEST(FourierTrajectory, BadFilesNameLineAndProblem) {
  const std::string head = "fundamental_hz: 0.1\njoints:\n";
  EXPECT_EQ(ErrorOf("fundamental_hz: 0\njoints:\n  - {q0: 0, a: [1], b: [1]}\n"),
            "exc.yaml:1:17: 'fundamental_hz': must be positive, got 0");
  EXPECT_EQ(ErrorOf("fundamental_hz: 0.1\n"), "exc.yaml:1:1: missing required key 'joints'");
  EXPECT_EQ(ErrorOf(head + "  - q0: 0\n    a: [1, 2]\n    b: [1]\n"),
            "exc.yaml:5:8: 'b' in 'joint 1': expected 2 numbers (as many as 'a'), got 1");
  EXPECT_EQ(ErrorOf(head + "  - {q0: 0, a: [1, 2], b: [1, 2]}\n  - {q0: 0, a: [1], b: [1]}\n"),
            "exc.yaml:4:16: 'a' in 'joint 2': expected 2 harmonics (as joint 1), got 1");
  EXPECT_EQ(ErrorOf(head + "  - {q0: zero, a: [1], b: [1], c: 2}\n"),
            "exc.yaml:3:10: 'q0' in 'joint 1': expected a number, got 'zero'\n"
            "exc.yaml:3:32: unknown key 'c' in 'joint 1' (known: a, b, name, q0)");
  EXPECT_EQ(ErrorOf(head + "  - {a: [1], b: [1]}\n"), "exc.yaml:3:5: missing required key 'q0' in 'joint 1'");
}

TEST(FourierTrajectory, ReferenceLogIsAContractArmLog) {
  const ArmModel model = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  FourierTrajectory t = RandomTrajectory(3, 3, 0.5, 5);  // 2 s period
  const CsvTable csv = ParseCsvTable(FormatReferenceCsv(model, t, 0.01, 2), "reference.csv");
  ASSERT_EQ(csv.rows.size(), 400u);  // two periods of 2 s at 10 ms
  const std::vector<std::string> want = {"t", "q1", "q2", "q3", "qd1", "qd2", "qd3", "qdd1", "qdd2", "qdd3",
                                         "qref1", "qref2", "qref3", "tau1", "tau2", "tau3"};
  EXPECT_EQ(csv.header, want);
  const std::size_t k = 137;
  const JointMotion m = EvaluateFourier(t, csv.rows[k][0]);
  EXPECT_NEAR(csv.rows[k][0], 1.37, 1e-12);
  const Eigen::VectorXd tau = InverseDynamics(model, m.q, m.qd, m.qdd);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(csv.rows[k][1 + i], m.q[i], 1e-9);
    EXPECT_NEAR(csv.rows[k][10 + i], m.q[i], 1e-9);
    EXPECT_NEAR(csv.rows[k][13 + i], tau[i], 1e-9);
  }
  EXPECT_THROW(FormatReferenceCsv(model, RandomTrajectory(2, 3, 0.5, 5), 0.01, 1), InputError);
}

}  // namespace
}  // namespace twinsim
