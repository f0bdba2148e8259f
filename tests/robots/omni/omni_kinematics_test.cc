#include "robots/omni/omni_kinematics.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "core/rng.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::Omni3;
using testing::Omni4;

void ExpectRoundTrip(const OmniModel& m) {
  OmniKinematics kin(m);
  Rng rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    Twist2 v{rng.Uniform(-3, 3), rng.Uniform(-3, 3), rng.Uniform(-10, 10)};
    Twist2 back = kin.BodyVelocity(kin.WheelSpeeds(v));
    EXPECT_NEAR(back.vx, v.vx, 1e-12);
    EXPECT_NEAR(back.vy, v.vy, 1e-12);
    EXPECT_NEAR(back.omega, v.omega, 1e-12);
  }
}

TEST(OmniKinematics, RoundTripThreeWheels) { ExpectRoundTrip(Omni3()); }
TEST(OmniKinematics, RoundTripFourWheels) { ExpectRoundTrip(Omni4()); }

TEST(OmniKinematics, WheelSpeedIsRollingSpeedOverRadius) {
  // Pure rotation: every wheel rolls at b * omega, so w = b omega / r.
  const OmniModel m = Omni4();
  OmniKinematics kin(m);
  Eigen::VectorXd w = kin.WheelSpeeds(Twist2{0, 0, 2.0});
  for (int i = 0; i < w.size(); ++i) EXPECT_NEAR(w[i], m.wheel_distance * 2.0 / m.wheel_radius, 1e-12);
  // Forward: wheel i rolls at -sin(alpha_i) vx.
  w = kin.WheelSpeeds(Twist2{1.0, 0, 0});
  for (int i = 0; i < w.size(); ++i) EXPECT_NEAR(w[i], -std::sin(m.wheel_angles[i]) / m.wheel_radius, 1e-12);
}

TEST(OmniKinematics, WrenchAndTorquesAreConsistent) {
  OmniKinematics kin(Omni4());
  const Eigen::Vector3d f(3.0, -2.0, 0.4);
  EXPECT_TRUE(kin.Wrench(kin.WheelTorques(f)).isApprox(f, 1e-12));
  // Power balance: torques . wheel speeds = wrench . body velocity.
  const Twist2 v{0.7, -0.3, 2.0};
  const Eigen::VectorXd tau = kin.WheelTorques(f);
  EXPECT_NEAR(tau.dot(kin.WheelSpeeds(v)), f.dot(Eigen::Vector3d(v.vx, v.vy, v.omega)), 1e-12);
}

TEST(OmniKinematics, FourWheelPseudoInverseRemovesInconsistentEncoderError) {
  // An encoder error no rigid motion explains (the left null space of J) vanishes.
  OmniKinematics kin(Omni4());
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(kin.wheels_from_body(), Eigen::ComputeFullU);
  const Eigen::VectorXd inconsistent = svd.matrixU().col(3);
  const Twist2 v{1.0, 0.5, 1.0};
  const Twist2 est = kin.BodyVelocity(kin.WheelSpeeds(v) + 5.0 * inconsistent);
  EXPECT_NEAR(est.vx, v.vx, 1e-12);
  EXPECT_NEAR(est.vy, v.vy, 1e-12);
  EXPECT_NEAR(est.omega, v.omega, 1e-12);
}

TEST(OmniKinematics, FourWheelsAverageRandomEncoderNoise) {
  // With independent noise on each wheel, the least-squares estimate from four wheels
  // has a smaller error than the exact solve from any three of them.
  const OmniModel m = Omni4();
  OmniKinematics kin(m);
  Rng rng(5);
  const int trials = 20000;
  const double sigma = 0.5;  // rad/s
  double err4 = 0, err3 = 0;
  const Eigen::MatrixXd j = kin.wheels_from_body();
  const Eigen::Matrix3d j3_inv = j.topRows(3).inverse();
  for (int t = 0; t < trials; ++t) {
    Eigen::VectorXd noise(4);
    for (int i = 0; i < 4; ++i) noise[i] = rng.Gaussian(sigma);
    const Twist2 e4 = kin.BodyVelocity(noise);
    const Eigen::Vector3d e3 = j3_inv * noise.head(3);
    err4 += e4.vx * e4.vx + e4.vy * e4.vy;
    err3 += e3[0] * e3[0] + e3[1] * e3[1];
  }
  EXPECT_LT(err4, 0.8 * err3) << "4-wheel RMS " << std::sqrt(err4 / trials) << " vs 3-wheel " << std::sqrt(err3 / trials);
  // And it matches the theory: covariance sigma^2 (J^T J)^{-1}.
  const Eigen::Matrix3d cov = sigma * sigma * (j.transpose() * j).inverse();
  EXPECT_NEAR(err4 / trials, cov(0, 0) + cov(1, 1), 0.05 * (cov(0, 0) + cov(1, 1)));
}

}  // namespace
}  // namespace twinsim
