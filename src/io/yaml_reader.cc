#include "io/yaml_reader.h"

#include <yaml-cpp/eventhandler.h>

#include <cmath>
#include <map>
#include <sstream>

#include "io/input_file.h"

namespace twinsim {
namespace {

std::string Describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  if (node.IsNull()) return "nothing";
  return "an undefined value";
}

std::string FormatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Finds keys that appear twice in one mapping, which yaml-cpp accepts silently (one of
// the two values is then lost without a word). Works on the parser's events, so an alias
// is one event and nothing is expanded.
class DuplicateKeyFinder : public YAML::EventHandler {
 public:
  explicit DuplicateKeyFinder(std::string name) : name_(std::move(name)) {}
  const std::vector<std::string>& problems() const { return problems_; }

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Node(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Node(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    Node(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    Node(mark, nullptr);
    frames_.push_back(Frame{false, true, {}});
  }
  void OnSequenceEnd() override { frames_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    Node(mark, nullptr);
    frames_.push_back(Frame{true, true, {}});
  }
  void OnMapEnd() override { frames_.pop_back(); }

 private:
  struct Frame {
    bool is_map = false;
    bool expect_key = true;
    std::map<std::string, int> key_lines;
  };

  // A node begins inside the innermost frame; `scalar` is its text when it is one.
  void Node(const YAML::Mark& mark, const std::string* scalar) {
    if (frames_.empty() || !frames_.back().is_map) return;
    Frame& f = frames_.back();
    if (f.expect_key && scalar != nullptr) {
      const auto [it, fresh] = f.key_lines.emplace(*scalar, mark.line + 1);
      if (!fresh && problems_.size() < 20) {
        problems_.push_back(SourceLocation{name_, mark.line + 1, mark.column + 1}.Prefix() + "duplicate key '" +
                            *scalar + "' (first on line " + std::to_string(it->second) + ")");
      }
    }
    f.expect_key = !f.expect_key;
  }

  std::string name_;
  std::vector<Frame> frames_;
  std::vector<std::string> problems_;
};

}  // namespace

YAML::Node LoadYamlString(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
    std::istringstream in(text);
    YAML::Parser parser(in);
    DuplicateKeyFinder finder(name);
    parser.HandleNextDocument(finder);
    if (!finder.problems().empty()) {
      ErrorList errors;
      for (const std::string& p : finder.problems()) errors.Add(p);
      errors.ThrowIfAny();
    }
  } catch (const YAML::ParserException& e) {
    SourceLocation where{name, e.mark.line + 1, e.mark.column + 1};
    throw InputError(where, "YAML syntax error: " + e.msg);
  }
  return root;
}

YAML::Node LoadYamlFile(const std::string& path) {
  YAML::Node root = LoadYamlString(ReadInputFile(path, "YAML", kMaxYamlBytes), path);
  if (!root.IsMap()) {
    throw InputError(SourceLocation{path, 1}, "expected a YAML mapping at the top level");
  }
  return root;
}

// Without a bound of its own, a positive quantity is still at most 1e12 (no quantity
// twinsim models comes near it; 1e308 is a typo that would overflow the physics).
NumberCheck Positive() { return Positive(1e12); }
NumberCheck NonNegative() { return NonNegative(1e12); }
NumberCheck Positive(double most) {
  return [most](double v) {
    if (!(v > 0)) return "must be positive, got " + FormatNumber(v);
    return v <= most ? std::string() : "must be at most " + FormatNumber(most) + ", got " + FormatNumber(v);
  };
}
NumberCheck NonNegative(double most) {
  return [most](double v) {
    if (!(v >= 0)) return "must not be negative, got " + FormatNumber(v);
    return v <= most ? std::string() : "must be at most " + FormatNumber(most) + ", got " + FormatNumber(v);
  };
}
NumberCheck InRange(double lo, double hi) {
  return [lo, hi](double v) {
    return (v >= lo && v <= hi) ? std::string()
                                : "must be in [" + FormatNumber(lo) + ", " + FormatNumber(hi) +
                                      "], got " + FormatNumber(v);
  };
}

std::optional<double> ReadNumber(const YAML::Node& node, const std::string& path,
                                 const std::string& label, ErrorList* errors) {
  SourceLocation where{path, node.Mark().line + 1, node.Mark().column + 1};
  if (!node.IsScalar()) {
    errors->Add(where, label + ": expected a number, got " + Describe(node));
    return std::nullopt;
  }
  const std::string& s = node.Scalar();
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end == s.c_str() || *end != '\0') {
    errors->Add(where, label + ": expected a number, got " + Describe(node));
    return std::nullopt;
  }
  if (!std::isfinite(v)) {
    errors->Add(where, label + ": must be a finite number, got " + Describe(node));
    return std::nullopt;
  }
  return v;
}

YamlMap::YamlMap(const YAML::Node& node, std::string path, std::string context, ErrorList* errors)
    : node_(node), path_(std::move(path)), context_(std::move(context)), errors_(errors) {
  if (!node_.IsMap()) {
    errors_->Add(Where(node_), "'" + context_ + "': expected a mapping, got " + Describe(node_));
    valid_ = false;
  }
}

SourceLocation YamlMap::Where(const YAML::Node& node) const {
  if (!node.IsDefined() || node.Mark().is_null()) return SourceLocation{path_};
  return SourceLocation{path_, node.Mark().line + 1, node.Mark().column + 1};
}

std::string YamlMap::Label(const std::string& key) const {
  return context_.empty() ? "'" + key + "'" : "'" + key + "' in '" + context_ + "'";
}

bool YamlMap::Has(const std::string& key) {
  known_.insert(key);
  return valid_ && node_[key].IsDefined() && !node_[key].IsNull();
}

YAML::Node YamlMap::Child(const std::string& key) {
  known_.insert(key);
  if (!valid_) return YAML::Node(YAML::NodeType::Undefined);
  return node_[key];
}

void YamlMap::Error(const std::string& key, const std::string& message) {
  YAML::Node n = valid_ ? node_[key] : YAML::Node();
  errors_->Add(n.IsDefined() ? Where(n) : Where(node_), Label(key) + ": " + message);
}

void YamlMap::Missing(const std::string& key) {
  errors_->Add(Where(node_), "missing required key " + Label(key));
}

namespace {

// Where a reader gives no range of its own: no quantity twinsim models comes near this,
// and a value beyond it (1e308 for a typo'd length) would overflow the physics.
std::string PlausibleMagnitude(double v) {
  constexpr double kMost = 1e12;
  if (std::abs(v) <= kMost) return {};
  return "must be within +-" + FormatNumber(kMost) + " (no quantity twinsim models comes near it), got " +
         FormatNumber(v);
}

}  // namespace

bool YamlMap::Get(const std::string& key, double* out, const NumberCheck& check) {
  if (!Has(key)) return false;
  auto v = ReadNumber(node_[key], path_, Label(key), errors_);
  if (!v) return false;
  {
    std::string problem = check ? check(*v) : PlausibleMagnitude(*v);
    if (!problem.empty()) {
      Error(key, problem);
      return false;
    }
  }
  *out = *v;
  return true;
}

bool YamlMap::Get(const std::string& key, int* out, const NumberCheck& check) {
  double v = *out;
  if (!Get(key, &v, check)) return false;
  if (v != std::floor(v) || std::abs(v) > 1e9) {
    Error(key, "expected a whole number, got '" + node_[key].Scalar() + "'");
    return false;
  }
  *out = static_cast<int>(v);
  return true;
}

bool YamlMap::Get(const std::string& key, bool* out) {
  if (!Has(key)) return false;
  const YAML::Node n = node_[key];
  if (n.IsScalar()) {
    const std::string& s = n.Scalar();
    if (s == "true" || s == "yes" || s == "on") { *out = true; return true; }
    if (s == "false" || s == "no" || s == "off") { *out = false; return true; }
  }
  Error(key, "expected true or false, got " + Describe(n));
  return false;
}

bool YamlMap::Get(const std::string& key, std::string* out, const std::vector<std::string>& allowed) {
  if (!Has(key)) return false;
  const YAML::Node n = node_[key];
  if (!n.IsScalar()) {
    Error(key, "expected a text value, got " + Describe(n));
    return false;
  }
  if (!allowed.empty()) {
    bool ok = false;
    std::string list;
    for (const auto& a : allowed) {
      ok = ok || a == n.Scalar();
      list += (list.empty() ? "" : ", ") + a;
    }
    if (!ok) {
      Error(key, "unknown value '" + n.Scalar() + "' (known: " + list + ")");
      return false;
    }
  }
  *out = n.Scalar();
  return true;
}

bool YamlMap::Get(const std::string& key, std::vector<double>* out, int size, const NumberCheck& check) {
  if (!Has(key)) return false;
  const YAML::Node n = node_[key];
  if (!n.IsSequence()) {
    Error(key, "expected a list of numbers, got " + Describe(n));
    return false;
  }
  if (size >= 0 && static_cast<int>(n.size()) != size) {
    Error(key, "expected " + std::to_string(size) + " numbers, got " + std::to_string(n.size()));
    return false;
  }
  std::vector<double> values;
  bool ok = true;
  for (std::size_t i = 0; i < n.size(); ++i) {
    auto v = ReadNumber(n[i], path_, Label(key) + "[" + std::to_string(i) + "]", errors_);
    if (!v) { ok = false; continue; }
    {
      std::string problem = check ? check(*v) : PlausibleMagnitude(*v);
      if (!problem.empty()) {
        errors_->Add(Where(n[i]), Label(key) + "[" + std::to_string(i) + "]: " + problem);
        ok = false;
        continue;
      }
    }
    values.push_back(*v);
  }
  if (ok) *out = values;
  return ok;
}

void YamlMap::Finish() {
  if (!valid_) return;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (known_.count(key)) continue;
    std::string list;
    for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
    // A key laid over an `extends:` base has no mark of its own; its value has one.
    // A copy: `it->` hands out a proxy that dies with this statement.
    const YAML::Node at = it->first.Mark().is_null() ? it->second : it->first;
    errors_->Add(Where(at), "unknown key '" + key + "'" +
                                       (context_.empty() ? "" : " in '" + context_ + "'") +
                                       " (known: " + list + ")");
  }
}

}  // namespace twinsim
