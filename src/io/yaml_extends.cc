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

std::string ModelFileRobot(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".urdf") return "arm";
  const YAML::Node root = ResolveExtends(LoadYamlFile(path), path, 0, [](const YAML::Node&, const std::string&, int) {});
  return root.IsMap() && root["robot"] && root["robot"].IsScalar() ? root["robot"].Scalar() : "omni";
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
