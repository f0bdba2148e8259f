// One list of engine names (core/engine_names.h): what the factories build is what the
// scene readers and the commands accept.
#include "core/engine_names.h"

#include <algorithm>

#include <gtest/gtest.h>

#include "core/error.h"
#include "engines/arm_engine.h"
#include "engines/omni_engine.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::Omni4;

TEST(EngineNames, EveryBuiltEngineIsAKnownOneAndTheLearnedBackendIsNoEngine) {
  for (const std::string& name : AvailableOmniEngines()) EXPECT_TRUE(IsKnownEngine(name)) << name;
  for (const std::string& name : AvailableArmEngines()) EXPECT_TRUE(IsKnownEngine(name)) << name;
  EXPECT_FALSE(IsKnownEngine("learned"));
  EXPECT_FALSE(IsKnownEngine("mujoco"));
  // The backends are the engines and the learned predictor, in that order.
  std::vector<std::string> engines = KnownBackends();
  ASSERT_EQ(engines.back(), "learned");
  engines.pop_back();
  EXPECT_EQ(engines, KnownEngines());
}

TEST(EngineNames, AKnownEngineThatIsNotBuiltSaysSoAndAnUnknownOneIsRefused) {
  const std::vector<std::string> built = AvailableOmniEngines();
  for (const std::string& name : KnownEngines()) {
    if (std::find(built.begin(), built.end(), name) != built.end()) {
      EXPECT_NE(MakeOmniEngine(name, {Omni4()}, FieldModel{}), nullptr) << name;
    } else {
      EXPECT_THROW(MakeOmniEngine(name, {Omni4()}, FieldModel{}), InputError) << name;
    }
  }
  EXPECT_THROW(MakeOmniEngine("mujoco", {Omni4()}, FieldModel{}), InputError);
}

}  // namespace
}  // namespace twinsim
