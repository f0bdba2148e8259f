#include "io/yaml_extends.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"
#include "io/yaml_reader.h"

namespace twinsim {
namespace {

void Overlay(YAML::Node base, const YAML::Node& over) {
  for (auto it = over.begin(); it != over.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (base[key].IsMap() && it->second.IsMap()) {
      Overlay(base[key], it->second);
    } else {
      base[key] = it->second;
    }
  }
}

}  // namespace

RobotKind ParseRobotKind(const YAML::Node& robot, const SourceLocation& where, const std::string& what) {
  if (robot.IsScalar() && robot.Scalar() == "arm") return RobotKind::kArm;
  if (robot.IsScalar() && robot.Scalar() == "omni") return RobotKind::kOmni;
  throw InputError(where, "'robot': expected arm (" + what + " of an arm) or omni (the default), got '" +
                              (robot.IsScalar() ? robot.Scalar() : std::string("a non-scalar")) + "'");
}

void RequireModelKind(const YAML::Node& root, const std::string& path, RobotKind wanted) {
  if (!root.IsMap()) return;
  const YAML::Node robot = root["robot"];
  const bool says = robot && robot.IsScalar();
  const bool omni = says ? robot.Scalar() == "omni" : static_cast<bool>(root["wheels"]);
  const bool arm = says && robot.Scalar() == "arm";
  if (wanted == RobotKind::kArm ? !omni : !arm) return;
  const SourceLocation where =
      says ? SourceLocation{path, robot.Mark().line + 1, robot.Mark().column + 1} : SourceLocation{path};
  throw InputError(where, wanted == RobotKind::kArm
                              ? "an omni robot's model, where an arm's is needed (a URDF, or YAML with robot: arm)"
                              : "an arm's model, where an omni robot's is needed (YAML with wheels, robot: omni)");
}

RobotKind ModelFileRobot(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".urdf") return RobotKind::kArm;
  // Each file's own `robot` checked where it is written, the file's or a base's.
  const auto check = [](const YAML::Node& root, const std::string& file, int) {
    if (!root.IsMap() || !root["robot"]) return;
    const YAML::Node robot = root["robot"];
    ParseRobotKind(robot, {file, robot.Mark().line + 1, robot.Mark().column + 1}, "a model");
  };
  const YAML::Node own = LoadYamlFile(path);
  check(own, path, 0);
  const YAML::Node root = ResolveExtends(own, path, 0, check);
  if (!root.IsMap() || !root["robot"]) return RobotKind::kOmni;
  return ParseRobotKind(root["robot"], {path}, "a model");
}

YAML::Node ResolveExtends(const YAML::Node& root, const std::string& path, int depth, const CheckBaseFile& check_base) {
  if (!root["extends"]) return root;
  const YAML::Node ext = root["extends"];
  const SourceLocation where{path, ext.Mark().line + 1, ext.Mark().column + 1};
  if (!ext.IsScalar()) throw InputError(where, "'extends': expected the path of a model file");
  if (depth > 8) throw InputError(where, "'extends' nested more than 8 deep (a cycle?)");
  std::filesystem::path base_path(ext.Scalar());
  if (base_path.is_relative()) base_path = std::filesystem::path(path).parent_path() / base_path;
  const std::string base_file = base_path.lexically_normal().string();
  check_base(LoadYamlFile(base_file), base_file, depth + 1);
  YAML::Node base = ResolveExtends(LoadYamlFile(base_file), base_file, depth + 1, check_base);
  Overlay(base, root);
  base.remove("extends");
  return base;
}

}  // namespace twinsim
