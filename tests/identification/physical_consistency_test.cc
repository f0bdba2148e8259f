// From base parameters back to physically consistent standard parameters.
#include "identification/physical_consistency.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/rng.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_regressor.h"
#include "test_util.h"

namespace twinsim {
namespace {

ArmModel PhysicalRrr() { return LoadArmModel(testing::SourcePath("models/rrr.yaml")); }

// The R factor of the base regressor over random states: the metric of a fit.
Eigen::MatrixXd RandomR(const ArmModel& m, const BaseParameters& base) {
  Eigen::MatrixXd w(3 * 200, base.rank());
  Rng rng(3);
  for (int k = 0; k < 200; ++k) {
    Eigen::VectorXd q(3), qd(3), qdd(3);
    for (int j = 0; j < 3; ++j) q[j] = rng.Uniform(-1, 1), qd[j] = rng.Uniform(-2, 2), qdd[j] = rng.Uniform(-5, 5);
    w.middleRows(3 * k, 3) = base.Reduce(Regressor(m, q, qd, qdd));
  }
  return w.householderQr().matrixQR().topRows(base.rank()).triangularView<Eigen::Upper>();
}

TEST(PhysicalConsistency, NearestParametersGiveBetaAndKeepTheAPrioriWhenTheyAlreadyDo) {
  const ArmModel m = PhysicalRrr();
  const BaseParameters base = IdentificationBase(m, {});
  const Eigen::VectorXd pi0 = StandardParameters(m);
  const Eigen::VectorXd beta0 = base.from_standard * pi0;
  EXPECT_LT((NearestStandardParameters(m, base.from_standard, beta0) - pi0).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::VectorXd beta = beta0;
  beta[0] += 0.05;
  const Eigen::VectorXd pi = NearestStandardParameters(m, base.from_standard, beta);
  EXPECT_LT((base.from_standard * pi - beta).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PhysicalConsistency, FindsConsistentParametersThatGiveBetaExactlyAtAnyWeight) {
  // An a-priori forearm ten times too thin; the truth is a real arm, so some consistent
  // parameters give its base parameters exactly, whatever the weights' scale.
  ArmModel a_priori = PhysicalRrr();
  a_priori.joints[2].child.inertia = Eigen::Vector3d(0.0002, 0.0016, 0.0016).asDiagonal();
  ArmModel truth = PhysicalRrr();
  truth.joints[2].child.inertia = Eigen::Vector3d(0.0024, 0.0168, 0.0152).asDiagonal();
  truth.joints[2].child.com = Eigen::Vector3d(0.15, 0.02, -0.01);
  truth.joints[1].child.com = Eigen::Vector3d(0.26, 0.01, 0.02);
  const BaseParameters base = IdentificationBase(a_priori, {});
  const Eigen::VectorXd beta = base.from_standard * StandardParameters(truth);
  // The minimum-norm correction is not a real forearm.
  EXPECT_NE(WithStandardParameters(a_priori, NearestStandardParameters(a_priori, base.from_standard, beta)).Validate(),
            "");
  const Eigen::MatrixXd r = RandomR(a_priori, base);
  for (double scale : {1.0, 1e3, 1e6}) {
    SCOPED_TRACE(scale);
    const ConsistentFit fit = FitConsistentParameters(a_priori, base.from_standard, scale * r, beta);
    EXPECT_TRUE(fit.converged);
    EXPECT_TRUE(fit.exact);
    EXPECT_LT(fit.iterations, 1000);
    EXPECT_EQ(WithStandardParameters(a_priori, fit.pi).Validate(), "");
    // Within 1e-3 of the weighted units, i.e. 1e-3 / scale in R's.
    EXPECT_LT((scale * r * (base.from_standard * fit.pi - beta)).norm(), 1e-3);
  }
}

TEST(PhysicalConsistency, BetaOfNoRealArmGivesTheBestConsistentCompromise) {
  // Negative Coulomb friction on joint 3: no real arm has it. The compromise keeps every
  // friction non-negative and fits the torques at least as well as simply clipping fc3
  // to zero (here far better: joint 3's viscous friction takes up part of it).
  const ArmModel m = PhysicalRrr();
  const BaseParameters base = IdentificationBase(m, {});
  Eigen::VectorXd pi = StandardParameters(m);
  const int fc3 = kParametersPerLink * 3 + 5;
  pi[fc3] = -0.3;
  const Eigen::VectorXd beta = base.from_standard * pi;
  const Eigen::MatrixXd r = RandomR(m, base);
  const ConsistentFit fit = FitConsistentParameters(m, base.from_standard, r, beta);
  EXPECT_TRUE(fit.converged);
  EXPECT_FALSE(fit.exact);
  EXPECT_EQ(WithStandardParameters(m, fit.pi).Validate(), "");
  EXPECT_LT(fit.pi[fc3], 1e-4);
  Eigen::VectorXd clipped = pi;
  clipped[fc3] = 0;
  const double misfit = (r * (base.from_standard * fit.pi - beta)).norm();
  const double clipped_misfit = (r * (base.from_standard * clipped - beta)).norm();
  EXPECT_LT(misfit, 0.9 * clipped_misfit);
  std::printf("misfit %.4g, clipping only %.4g\n", misfit, clipped_misfit);
}

TEST(PhysicalConsistency, RefusesAnUnphysicalAPrioriModel) {
  ArmModel m = PhysicalRrr();
  m.joints[1].child.inertia = Eigen::Vector3d(0.001, 0.001, 0.05).asDiagonal();
  const BaseParameters base = IdentificationBase(PhysicalRrr(), {});
  EXPECT_THROW(FitConsistentParameters(m, base.from_standard, Eigen::MatrixXd::Identity(21, 21),
                                       Eigen::VectorXd::Zero(21)),
               InputError);
}

}  // namespace
}  // namespace twinsim
