// ILC that stays converged (issue 30): the shipped writing scene over 50 trials, and
// the filters it measured and fitted run on plants they were not fitted to. The cause
// of the slow growth the safeguard answers is measured in docs/ilc.md ("Staying
// converged"): without friction the same design converges monotonically.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <string>

#include "control/iterative_learning.h"
#include "robots/arm/arm_model.h"
#include "scene/arm_scene.h"
#include "scene/ilc_scene.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

// Each joint's RMS error of the last trial over its best trial's.
Eigen::VectorXd LastOverBest(const IlcResult& r) {
  Eigen::VectorXd best = r.error_rms.front();
  for (const Eigen::VectorXd& e : r.error_rms) best = best.cwiseMin(e);
  return r.error_rms.back().cwiseQuotient(best);
}

// The shipped scene, 50 trials: every joint within 1.2 times its best at the end, and
// still 10 times lower within 7 trials. Without the safeguard the shoulder ends 10.6
// times above its best (docs/ilc.md).
TEST(IlcSafeguard, ShippedSceneStaysWithinItsBestOverFiftyTrials) {
  const ArmScene scene = LoadArmScene(SourcePath("scenes/rrr_writing_ilc.yaml"));
  const IlcSceneRun run = RunIlcScene(scene, "", 50);
  const IlcResult& r = run.result;
  SCOPED_TRACE(r.FullReport());
  const Eigen::VectorXd ratio = LastOverBest(r);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LE(ratio[j], 1.2) << "joint " << j + 1;
    EXPECT_GE(r.error_rms[0][j] / r.error_rms[7][j], 10) << "joint " << j + 1;
  }
  EXPECT_FALSE(r.safeguard.empty());  // the shoulder's friction makes it act
  for (const IlcSafeguardEvent& e : r.safeguard) EXPECT_GT(e.rms, scene.ilc.options.safeguard.growth * e.best_rms);

  // Off: the growth the issue measured comes back.
  ArmScene off = scene;
  off.ilc.options.safeguard.growth = 0;
  const IlcResult unguarded = RunIlcScene(off, "", 50).result;
  EXPECT_TRUE(unguarded.safeguard.empty());
  EXPECT_GT(LastOverBest(unguarded).maxCoeff(), 3) << unguarded.FullReport();
}

// Plants the filters were not fitted to: the shipped scene's measurement, filters and
// cutoffs, then 50 trials on a plant with three times the payload, 4 ms more command
// delay, or twice the friction. No joint ends above 1.5 times its best; none diverges.
struct Plant {
  std::string label;
  std::string yaml;  // over models/rrr_plant.yaml
};

void PrintTo(const Plant& p, std::ostream* os) { *os << p.label; }

class IlcUnfittedPlant : public ::testing::TestWithParam<Plant> {};

TEST_P(IlcUnfittedPlant, StaysWithinOneAndAHalfTimesItsBest) {
  const ArmScene scene = LoadArmScene(SourcePath("scenes/rrr_writing_ilc.yaml"));
  const IlcSceneRun fitted = RunIlcScene(scene, "", 0);
  const ArmModel plant = LoadArmModelFromYamlString(
      "extends: " + SourcePath("models/rrr_plant.yaml") + "\nname: " + GetParam().label + "\n" + GetParam().yaml,
      GetParam().label + ".yaml");
  const IlcResult r = RunIlc(plant, scene.hat, fitted.reference, fitted.tracking, fitted.filters,
                             [&] {
                               IlcOptions o = fitted.options;
                               o.trials = 50;
                               return o;
                             }());
  SCOPED_TRACE(r.FullReport());
  const Eigen::VectorXd ratio = LastOverBest(r);
  if (std::getenv("TWINSIM_PRINT_ILC")) {
    std::cout << GetParam().label << ": trial 0 " << r.error_rms[0].transpose() << ", trial 50 "
              << r.error_rms[50].transpose() << ", last/best " << ratio.transpose() << ", safeguard acted "
              << r.safeguard.size() << " times\n";
  }
  for (int j = 0; j < 3; ++j) EXPECT_LE(ratio[j], 1.5) << "joint " << j + 1;
  EXPECT_FALSE(r.Diverged());
  // Learned, not only held: twice the friction leaves the elbow 9.6 times lower (docs/ilc.md).
  EXPECT_LT(r.WorstRms(50), 0.2 * r.WorstRms(0));
}

INSTANTIATE_TEST_SUITE_P(
    Plants, IlcUnfittedPlant,
    ::testing::Values(
        Plant{"payload_x3",
              "effects:\n"
              "  - {name: torque_offset, joint: shoulder, tau0: 1.2}\n"
              "  - {name: stribeck_friction, joint: elbow, c: 0.4, s: 1.0, vs: 0.1}\n"
              "  - {name: viscous_friction, joint: waist, b: 0.6}\n"
              "  - {name: coulomb_friction, joint: shoulder, c_pos: 0.8, c_neg: 0.4}\n"
              "  - {name: payload, joint: null, mass: 1.5, x: 0.35}\n"},
        Plant{"delay_plus_4ms", "delay_samples: 5\n"},
        Plant{"friction_x2",
              "effects:\n"
              "  - {name: torque_offset, joint: shoulder, tau0: 1.2}\n"
              "  - {name: stribeck_friction, joint: elbow, c: 0.8, s: 2.0, vs: 0.1}\n"
              "  - {name: viscous_friction, joint: waist, b: 1.2}\n"
              "  - {name: coulomb_friction, joint: shoulder, c_pos: 1.6, c_neg: 0.8}\n"
              "  - {name: payload, joint: null, mass: 0.5, x: 0.35}\n"}),
    [](const ::testing::TestParamInfo<Plant>& info) { return info.param.label; });

}  // namespace
}  // namespace twinsim
