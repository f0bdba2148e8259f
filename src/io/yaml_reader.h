// Reading the project's YAML files (scenes, omni models) into plain structs.
//
// LoadYamlFile() parses a file and turns syntax errors into InputError with
// "path:line:column:". YamlMap wraps one mapping: Get()/Require() read typed values with
// their defaults kept when absent, every problem goes into a shared ErrorList, and
// Finish() reports unknown keys with the list of known ones:
//
//   ErrorList errors;
//   YamlMap m(root, path, "wheel", &errors);
//   m.Get("radius", &wheel.radius, Positive());
//   m.Finish();
//   errors.ThrowIfAny();
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace twinsim {

// The largest YAML file read (models, scenes, predictors with their weights).
inline constexpr std::uintmax_t kMaxYamlBytes = std::uintmax_t{256} << 20;

// Parses `path`; throws InputError naming the file (and line) when it cannot: a syntax
// error, a key given twice in one mapping (both lines named), a folder, a huge file.
YAML::Node LoadYamlFile(const std::string& path);
// Parses YAML text; `name` stands for the file in messages.
YAML::Node LoadYamlString(const std::string& text, const std::string& name);

// A check on a number: returns an empty string when fine, else what is wrong.
using NumberCheck = std::function<std::string(double)>;
NumberCheck Positive();
NumberCheck NonNegative();
// 0 < v <= most (a physical bound: a robot of 1e308 kg is a typo, and breaks the engines).
NumberCheck Positive(double most);
// 0 <= v <= most.
NumberCheck NonNegative(double most);
NumberCheck InRange(double lo, double hi);  // lo <= v <= hi

class YamlMap {
 public:
  // `context` names the mapping in messages ("wheel 2", "controller.forward").
  YamlMap(const YAML::Node& node, std::string path, std::string context, ErrorList* errors);

  bool valid() const { return valid_; }
  bool Has(const std::string& key);
  // The child node (marks the key as known); an undefined node when absent.
  YAML::Node Child(const std::string& key);

  // Reads an optional value; leaves *out unchanged when the key is absent.
  // Returns true when a valid value was read.
  bool Get(const std::string& key, double* out, const NumberCheck& check = {});
  bool Get(const std::string& key, int* out, const NumberCheck& check = {});
  bool Get(const std::string& key, bool* out);
  bool Get(const std::string& key, std::string* out,
           const std::vector<std::string>& allowed = {});
  bool Get(const std::string& key, std::vector<double>* out, int size = -1,
           const NumberCheck& check = {});

  // As Get(), but the key must be present.
  template <typename T, typename... Args>
  bool Require(const std::string& key, T* out, Args&&... args) {
    if (!Has(key)) {
      Missing(key);
      return false;
    }
    return Get(key, out, std::forward<Args>(args)...);
  }

  // Reports a problem at `key` (or at the mapping when the key is absent).
  void Error(const std::string& key, const std::string& message);
  void Missing(const std::string& key);
  // Reports every key that no Get/Require/Has/Child asked for.
  void Finish();

  SourceLocation Where(const YAML::Node& node) const;
  SourceLocation Where() const { return Where(node_); }
  const std::string& path() const { return path_; }
  const std::string& context() const { return context_; }
  ErrorList* errors() const { return errors_; }

 private:
  std::string Label(const std::string& key) const;

  YAML::Node node_;
  std::string path_;
  std::string context_;
  ErrorList* errors_;
  std::set<std::string> known_;
  bool valid_ = true;
};

// Reads a node as a number with a clear error; nullopt (and an error) on failure.
std::optional<double> ReadNumber(const YAML::Node& node, const std::string& path,
                                 const std::string& label, ErrorList* errors);

}  // namespace twinsim
