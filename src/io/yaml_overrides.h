// Setting keys of a YAML document from outside its file: a batch sweep's parameters
// (`plant.body.mass: 2.4`, `scene.robots.0.commands.speed: 1.0`) laid over a model or a
// scene before it is read, so that a variant goes through the same reader, checks and
// messages as the file itself.
//
// A key is a dotted path: mapping keys by name, list entries by their 0-based index.
// Missing mappings on the way are created; a list index must exist. The new values
// carry no file position, so a reader's complaint about one names the file and the key
// without a line.
//
//   YAML::Node root = LoadYamlFile("models/omni4.yaml");
//   root = ApplyYamlOverrides(root, {{"body.mass", YAML::Node(2.4)}}, "models/omni4.yaml");
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace twinsim {

struct YamlOverride {
  std::string key;   // dotted path, e.g. "effects.traction_limit.a_max"
  YAML::Node value;  // any YAML value (a scalar, a list, a mapping)
};
using YamlOverrides = std::vector<YamlOverride>;

// A deep copy of `root` with every override set in order. Throws InputError (naming
// `path`, the document's file) for an empty key or step, a step into a scalar, or a
// list index that is not a number or out of range.
YAML::Node ApplyYamlOverrides(const YAML::Node& root, const YamlOverrides& overrides, const std::string& path);

}  // namespace twinsim
