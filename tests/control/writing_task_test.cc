// The writing task's path and the RRR arm's closed-form inverse kinematics.
#include "control/writing_task.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "test_util.h"

namespace twinsim {
namespace {

ArmModel Rrr() { return LoadArmModel(testing::SourcePath("models/rrr.yaml")); }

TEST(WritingTask, CornersSpanTheLettersBox) {
  WritingTaskOptions o;  // "TUE", 0.25 m tall, 0.15 m wide, 0.075 m gaps
  const Eigen::Matrix3Xd c = WritingTaskCorners(o);
  // T: 4 corners, U: 4, E: 7, no duplicates at the joins.
  EXPECT_EQ(c.cols(), 15);
  EXPECT_NEAR(c.row(0).minCoeff(), 0.45, 1e-15);
  EXPECT_NEAR(c.row(0).maxCoeff(), 0.45, 1e-15);
  // Three letters 0.15 wide with two 0.075 gaps: 0.6 m, centred on y = 0.
  EXPECT_NEAR(c.row(1).maxCoeff(), 0.30, 1e-12);
  EXPECT_NEAR(c.row(1).minCoeff(), -0.30, 1e-12);
  EXPECT_NEAR(c.row(2).minCoeff(), 0.175, 1e-12);
  EXPECT_NEAR(c.row(2).maxCoeff(), 0.425, 1e-12);
  // The T's top bar starts at the text's left (+y) top corner.
  EXPECT_NEAR(c(1, 0), 0.30, 1e-12);
  EXPECT_NEAR(c(2, 0), 0.425, 1e-12);
}

TEST(WritingTask, RejectsBadOptions) {
  WritingTaskOptions o;
  std::string why;
  o.letters = "TQE";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "letter 'Q' has no strokes (known: AEFHILMNRTUVWZ)");
  o = {};
  o.speed = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "speed must be > 0 (m/s)");
  o = {};
  o.letters = "  ";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THROW(WritingTaskReference(Rrr(), o), InputError);
}

TEST(WritingTask, IkRoundTripHitsThePointsWithin1e9) {
  const ArmModel arm = Rrr();
  WritingTaskOptions o;
  for (const std::string& letters : {std::string("TUE"), std::string("RRR"), std::string("AMWZ")}) {
    o.letters = letters;
    o.height = letters.size() > 3 ? 0.2 : 0.25;
    const Eigen::Matrix3Xd c = WritingTaskCorners(o);
    for (Eigen::Index k = 0; k < c.cols(); ++k) {
      const Eigen::VectorXd q = WaistShoulderElbowIk(arm, c.col(k), o.tool);
      EXPECT_LT((ToolPoint(arm, q, o.tool) - c.col(k)).norm(), 1e-9) << letters << " corner " << k;
      EXPECT_LT(q(2), 0) << "elbow up";
    }
  }
}

TEST(WritingTask, IkMatchesAKnownPosture) {
  // Stretched along +x at the shoulder's height: q = 0 (acos near 1 loses half the
  // digits: 1e-7). Upper arm straight up (q2 = pi/2), forearm level (q3 = -pi/2), waist
  // at 30 degrees: the tool 0.35 m out from the waist axis at z = 0.30 + 0.40 m.
  const ArmModel arm = Rrr();
  const Eigen::Vector3d tool(0.35, 0, 0);
  EXPECT_LT(WaistShoulderElbowIk(arm, Eigen::Vector3d(0.75, 0, 0.30), tool).norm(), 1e-7);
  const double a = kPi / 6;
  const Eigen::Vector3d p(0.35 * std::cos(a), 0.35 * std::sin(a), 0.70);
  const Eigen::VectorXd q = WaistShoulderElbowIk(arm, p, tool);
  EXPECT_NEAR(q(0), a, 1e-12);
  EXPECT_NEAR(q(1), kPi / 2, 1e-12);
  EXPECT_NEAR(q(2), -kPi / 2, 1e-12);
}

TEST(WritingTask, IkRejectsUnreachablePoints) {
  const ArmModel arm = Rrr();
  const Eigen::Vector3d tool(0.35, 0, 0);
  try {
    WaistShoulderElbowIk(arm, Eigen::Vector3d(0.9, 0, 0.3), tool);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("out of reach of 'rrr' (distance 0.9 m from the shoulder, reach 0.05 to 0.75 m)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(WaistShoulderElbowIk(arm, Eigen::Vector3d(0, 0, 0.5), tool), InputError);  // on the axis
  // Behind the arm: waist beyond its 170 degree limit.
  EXPECT_THROW(WaistShoulderElbowIk(arm, Eigen::Vector3d(-0.5, 0.01, 0.3), tool), InputError);
  WritingTaskOptions o;
  o.plane_x = 0.8;  // the letters beyond reach
  EXPECT_THROW(WritingTaskReference(arm, o), InputError);
}

TEST(WritingTask, JacobianBiasMatchesFiniteDifferences) {
  const ArmModel arm = Rrr();
  const Eigen::Vector3d tool(0.35, 0, 0);
  const Eigen::Vector3d q(0.3, 0.4, -1.1), qd(1.2, -0.7, 2.1);
  const double e = 1e-6;
  // J: columns against central differences of the tool point (error O(e^2) ~ 1e-12).
  const Eigen::MatrixXd jac = ToolJacobian(arm, q, tool);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d dq = Eigen::Vector3d::Unit(i) * e;
    const Eigen::Vector3d fd = (ToolPoint(arm, q + dq, tool) - ToolPoint(arm, q - dq, tool)) / (2 * e);
    EXPECT_LT((jac.col(i) - fd).norm(), 1e-8);
  }
  // Jd qd = d/ds J(q + s qd) qd at s = 0.
  const Eigen::Vector3d fd =
      (ToolJacobian(arm, q + e * qd, tool) - ToolJacobian(arm, q - e * qd, tool)) * qd / (2 * e);
  EXPECT_LT((ToolBiasAcceleration(arm, q, qd, tool) - fd).norm(), 1e-7);
}

TEST(WritingTask, ReferenceIsConsistentAndWithinLimits) {
  const ArmModel arm = Rrr();
  WritingTaskOptions o;
  const ArmReference ref = WritingTaskReference(arm, o);
  const Eigen::Index n = ref.t.size();
  ASSERT_GT(n, 1000);
  EXPECT_DOUBLE_EQ(ref.sample_time, 0.001);
  EXPECT_NEAR(ref.t(n - 1), (n - 1) * 0.001, 1e-12);
  // Every sample on the path: FK(q) = p within 1e-9 m, and the plane x = 0.45.
  double worst = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    worst = std::max(worst, (ToolPoint(arm, ref.q.row(k).transpose(), o.tool) - ref.p.row(k).transpose()).norm());
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT((ref.p.col(0).array() - 0.45).abs().maxCoeff(), 1e-12);
  // Speed and acceleration never exceed the options'.
  EXPECT_LE(ref.pd.rowwise().norm().maxCoeff(), o.speed * (1 + 1e-12));
  EXPECT_NEAR(ref.pdd.rowwise().norm().maxCoeff(), o.acceleration, 1e-9);
  // Joint limits: positions, and velocities under the 6 rad/s limits.
  for (int j = 0; j < 3; ++j) {
    EXPECT_GE(ref.q.col(j).minCoeff(), arm.joints[j].lower);
    EXPECT_LE(ref.q.col(j).maxCoeff(), arm.joints[j].upper);
    EXPECT_LE(ref.qd.col(j).cwiseAbs().maxCoeff(), arm.joints[j].velocity_limit);
  }
  // Starts and ends at rest.
  EXPECT_EQ(ref.qd.row(0).norm(), 0);
  EXPECT_EQ(ref.qd.row(n - 1).norm(), 0);
  // qd and qdd are the derivatives of q and qd: central differences agree with them
  // within Ts/2 max|qdd| for qd (qdd jumps between samples), and for qdd away from
  // the jumps (4 per stroke, each spoiling at most 2 samples) within 1% of max|qdd|
  // (the rest is O(Ts^2) from the joints' jerk of the curved joint path).
  const double ts = ref.sample_time;
  for (int j = 0; j < 3; ++j) {
    const double acc_max = ref.qdd.col(j).cwiseAbs().maxCoeff();
    double qd_err = 0;
    int qdd_off = 0;
    for (Eigen::Index k = 1; k + 1 < n; ++k) {
      qd_err = std::max(qd_err, std::abs((ref.q(k + 1, j) - ref.q(k - 1, j)) / (2 * ts) - ref.qd(k, j)));
      if (std::abs((ref.qd(k + 1, j) - ref.qd(k - 1, j)) / (2 * ts) - ref.qdd(k, j)) > 0.01 * acc_max) ++qdd_off;
    }
    EXPECT_LT(qd_err, 0.5 * ts * acc_max) << "joint " << j;
    EXPECT_LT(qdd_off, 2 * 4 * 14 + 2) << "joint " << j;  // 14 strokes in "TUE"
  }
}

}  // namespace
}  // namespace twinsim
