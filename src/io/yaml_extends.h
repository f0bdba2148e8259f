// `extends: BASE.yaml` for the project's model files: a file starts from another and
// lays its own keys over it (mappings merge key by key, anything else, lists included,
// replaces). Nodes keep their marks, so messages still point into the right file.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <string>

#include "core/error.h"
#include "core/robot_kind.h"

namespace twinsim {

// Reads a model file's YAML (with its own `extends` resolved) at nesting `depth`; used
// to check a base on its own first, so that its problems name its own file.
using CheckBaseFile = std::function<void(const YAML::Node& root, const std::string& path, int depth)>;

// Returns `root` with its `extends` chain resolved (paths relative to the file). Throws
// InputError for a non-text `extends`, a chain deeper than 8 (a cycle), or whatever
// `check_base` throws for a base file.
YAML::Node ResolveExtends(const YAML::Node& root, const std::string& path, int depth, const CheckBaseFile& check_base);

// The kind of robot a model file describes: an arm for URDF (.urdf), else the `robot`
// value of the YAML with its `extends` chain resolved (omni when absent), so that a file
// extending an arm's is an arm's. Throws InputError when the YAML cannot be read or
// `robot` is neither arm nor omni.
RobotKind ModelFileRobot(const std::string& path);

// Throws one InputError, at the file's `robot` key, where a model file's resolved `root`
// is the other kind's than `wanted` (`robot: omni`, or none and an omni robot's
// `wheels`, where an arm's is wanted; `robot: arm` where an omni robot's is): the model
// reader's own checks would list every key of the other schema instead.
void RequireModelKind(const YAML::Node& root, const std::string& path, RobotKind wanted);

// A `robot:` value: arm or omni; InputError at `where` (the key's place) for anything else,
// `what` saying what the file is ("a model", "a scene").
RobotKind ParseRobotKind(const YAML::Node& robot, const SourceLocation& where, const std::string& what);

}  // namespace twinsim
