// `extends: BASE.yaml` for the project's model files: a file starts from another and
// lays its own keys over it (mappings merge key by key, anything else, lists included,
// replaces). Nodes keep their marks, so messages still point into the right file.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <string>

namespace twinsim {

// Reads a model file's YAML (with its own `extends` resolved) at nesting `depth`; used
// to check a base on its own first, so that its problems name its own file.
using CheckBaseFile = std::function<void(const YAML::Node& root, const std::string& path, int depth)>;

// Returns `root` with its `extends` chain resolved (paths relative to the file). Throws
// InputError for a non-text `extends`, a chain deeper than 8 (a cycle), or whatever
// `check_base` throws for a base file.
YAML::Node ResolveExtends(const YAML::Node& root, const std::string& path, int depth, const CheckBaseFile& check_base);

// The kind of robot a model file describes: "arm" for URDF (.urdf), else the `robot`
// value of the YAML with its `extends` chain resolved ("omni" when absent), so that a
// file extending an arm's is an arm's. Throws InputError when the YAML cannot be read.
std::string ModelFileRobot(const std::string& path);

}  // namespace twinsim
