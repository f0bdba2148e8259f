#include "io/yaml_overrides.h"

#include <cctype>
#include <sstream>

#include "core/error.h"

namespace twinsim {
namespace {

std::vector<std::string> SplitKey(const std::string& key) {
  std::vector<std::string> steps;
  std::stringstream in(key);
  std::string step;
  while (std::getline(in, step, '.')) steps.push_back(step);
  if (!key.empty() && key.back() == '.') steps.push_back("");
  return steps;
}

bool IsIndex(const std::string& s) {
  if (s.empty() || s.size() > 9) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

}  // namespace

YAML::Node ApplyYamlOverrides(const YAML::Node& root, const YamlOverrides& overrides, const std::string& path) {
  YAML::Node out = YAML::Clone(root);
  if (!out.IsDefined() || out.IsNull()) out = YAML::Node(YAML::NodeType::Map);
  for (const YamlOverride& o : overrides) {
    const std::vector<std::string> steps = SplitKey(o.key);
    const auto fail = [&](const std::string& why) {
      throw InputError(SourceLocation{path}, "cannot set '" + o.key + "': " + why);
    };
    if (steps.empty()) fail("the key is empty");
    // yaml-cpp nodes are handles: `node = node[...]` would assign through them, so the
    // walk keeps its position in a vector of handles instead.
    std::vector<YAML::Node> walk{out};
    for (std::size_t i = 0; i < steps.size(); ++i) {
      const std::string& step = steps[i];
      if (step.empty()) fail("empty step in the key");
      const YAML::Node here = walk.back();
      const bool last = i + 1 == steps.size();
      if (here.IsSequence()) {
        if (!IsIndex(step)) fail("'" + step + "' must be a list index (0, 1, ...) into a list");
        const std::size_t index = std::stoul(step);
        if (index >= here.size())
          fail("index " + step + " is beyond the list's " + std::to_string(here.size()) + " entries");
        YAML::Node slot = here;
        if (last) {
          slot[index] = YAML::Clone(o.value);
        } else {
          walk.push_back(slot[index]);
        }
      } else if (here.IsMap() || here.IsNull()) {
        YAML::Node slot = here;
        if (last) {
          slot[step] = YAML::Clone(o.value);
        } else {
          YAML::Node child = slot[step];
          if (!child.IsDefined() || child.IsNull()) {
            slot[step] = YAML::Node(YAML::NodeType::Map);
            child = slot[step];
          }
          walk.push_back(child);
        }
      } else {
        fail(i == 0 ? std::string("the document is a single value, not a mapping")
                    : "'" + steps[i - 1] + "' holds a single value, not a mapping or a list");
      }
    }
  }
  return out;
}

}  // namespace twinsim
