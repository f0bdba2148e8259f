#include "io/yaml_extends.h"

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
