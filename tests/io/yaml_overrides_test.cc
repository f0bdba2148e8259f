#include "io/yaml_overrides.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/yaml_reader.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

TEST(YamlOverrides, SetsNestedKeysCreatesMappingsAndLeavesTheOriginal) {
  const YAML::Node root = LoadYamlString("a: {b: 1}\nlist: [{x: 1}, {x: 2}]\n", "t.yaml");
  const YAML::Node out = ApplyYamlOverrides(
      root, {{"a.b", YAML::Node(5)}, {"a.c.d", YAML::Node("text")}, {"list.1.x", YAML::Node(7)}}, "t.yaml");
  EXPECT_EQ(out["a"]["b"].as<int>(), 5);
  EXPECT_EQ(out["a"]["c"]["d"].as<std::string>(), "text");
  EXPECT_EQ(out["list"][0]["x"].as<int>(), 1);
  EXPECT_EQ(out["list"][1]["x"].as<int>(), 7);
  EXPECT_EQ(root["a"]["b"].as<int>(), 1);  // a copy was changed, not the document
  EXPECT_FALSE(root["a"]["c"]);
  EXPECT_EQ(root["list"][1]["x"].as<int>(), 2);
}

TEST(YamlOverrides, RefusesStepsThatCannotBeFollowed) {
  const YAML::Node root = LoadYamlString("a: 1\nlist: [1, 2]\n", "t.yaml");
  const auto message = [&](const std::string& key) {
    try {
      ApplyYamlOverrides(root, {{key, YAML::Node(1)}}, "t.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("a.b"), "t.yaml: cannot set 'a.b': 'a' holds a single value, not a mapping or a list");
  EXPECT_EQ(message("list.2"), "t.yaml: cannot set 'list.2': index 2 is beyond the list's 2 entries");
  EXPECT_EQ(message("list.x"), "t.yaml: cannot set 'list.x': 'x' must be a list index (0, 1, ...) into a list");
  EXPECT_EQ(message("a..b"), "t.yaml: cannot set 'a..b': empty step in the key");
}

TEST(YamlOverrides, AModelVariantGoesThroughTheModelsOwnChecks) {
  const std::string path = SourcePath("models/omni4.yaml");
  const OmniModel nominal = LoadOmniModel(path);
  const OmniModel heavy = LoadOmniModel(path, {{"chassis.mass", YAML::Node(3.5)}});
  EXPECT_DOUBLE_EQ(heavy.chassis_mass, 3.5);
  EXPECT_NE(nominal.chassis_mass, 3.5);
  // Through `extends:` too: the slipping plant's limit, then the file's own keys.
  const OmniModel slipping = LoadOmniModel(SourcePath("models/omni4_slipping.yaml"),
                                           {{"effects.traction_limit.a_max", YAML::Node(2.0)}});
  EXPECT_DOUBLE_EQ(slipping.effects.a_max, 2.0);
  try {
    LoadOmniModel(path, {{"chassis.mas", YAML::Node(3.0)}});
    FAIL() << "a misspelt key was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key 'mas'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LoadOmniModel(path, {{"chassis.mass", YAML::Node(-1.0)}}), InputError);
  const ArmModel payload = LoadArmModel(SourcePath("models/rrr_plant.yaml"), {{"effects.4.mass", YAML::Node(0.9)}});
  EXPECT_DOUBLE_EQ(payload.effects.payload_mass, 0.9);
}

}  // namespace
}  // namespace twinsim
