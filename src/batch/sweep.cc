#include "batch/sweep.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/rng.h"
#include "io/yaml_reader.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kCommands = {"run", "replay", "compare"};
const std::vector<std::string> kInputs = {"scene", "model", "log", "predictor", "backend", "backends", "horizon", "seed"};
const std::vector<std::string> kPathInputs = {"scene", "model", "log", "predictor"};
const std::vector<std::string> kKeyPrefixes = {"scene.", "plant.", "model."};
const std::vector<std::string> kDistributions = {"uniform", "log_uniform", "integer", "choice"};

bool IsPathInput(const std::string& name) {
  return std::find(kPathInputs.begin(), kPathInputs.end(), name) != kPathInputs.end();
}

SourceLocation Where(const std::string& path, const YAML::Node& node) {
  if (!node.IsDefined() || node.Mark().is_null()) return SourceLocation{path};
  return SourceLocation{path, node.Mark().line + 1, node.Mark().column + 1};
}

// Checks a parameter's name; reports at `where`.
bool CheckName(const std::string& name, const SourceLocation& where, ErrorList* errors) {
  if (std::find(kInputs.begin(), kInputs.end(), name) != kInputs.end()) return true;
  for (const std::string& prefix : kKeyPrefixes) {
    if (name.rfind(prefix, 0) == 0) {
      if (name.size() == prefix.size() || name.back() == '.' || name.find("..") != std::string::npos) {
        errors->Add(where, "parameter '" + name + "': expected a key after '" + prefix + "' (e.g. " + prefix +
                               "body.mass)");
        return false;
      }
      return true;
    }
  }
  errors->Add(where, "unknown parameter '" + name +
                         "' (known: scene, model, log, predictor, backend, backends, horizon, seed, and keys set in "
                         "the files as scene.KEY, plant.KEY, model.KEY)");
  return false;
}

std::string ValueText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

// A value of parameter `name` from the sweep file at `file`: paths become relative to
// the working folder, the text stays as written.
bool ReadValue(const std::string& name, const YAML::Node& node, const std::string& file, ErrorList* errors,
               SweepValue* out) {
  const SourceLocation where = Where(file, node);
  if (!node.IsDefined() || node.IsNull()) {
    errors->Add(where, "parameter '" + name + "': expected a value");
    return false;
  }
  out->text = ValueText(node);
  out->node = YAML::Clone(node);
  if (IsPathInput(name)) {
    if (!node.IsScalar()) {
      errors->Add(where, "parameter '" + name + "': expected a file path");
      return false;
    }
    fs::path p(node.Scalar());
    if (p.is_relative()) p = fs::path(file).parent_path() / p;
    const std::string resolved = p.lexically_normal().string();
    std::error_code ec;
    if (!fs::is_regular_file(resolved, ec)) {
      errors->Add(where, "parameter '" + name + "': no file '" + resolved + "'");
      return false;
    }
    out->node = YAML::Node(resolved);
  } else if (name == "horizon" || name == "seed") {
    const std::optional<double> v = ReadNumber(node, file, "parameter '" + name + "'", errors);
    if (!v) return false;
    if (*v < 0 || *v != std::floor(*v) || *v > 9007199254740992.0) {
      errors->Add(where, "parameter '" + name + "': expected a whole number >= 0, got " + out->text);
      return false;
    }
  } else if (name == "backends") {
    if (!node.IsSequence() || node.size() == 0) {
      errors->Add(where, "parameter 'backends': expected a list of backends, e.g. [ode, analytic]");
      return false;
    }
  }
  return true;
}

void Replace(std::vector<SweepParameter>* list, SweepParameter p) {
  for (SweepParameter& q : *list) {
    if (q.name == p.name) {
      q = std::move(p);
      return;
    }
  }
  list->push_back(std::move(p));
}

void ReadParameterBlock(const YAML::Node& node, const std::string& file, const std::string& block, bool grid,
                        ErrorList* errors, std::vector<SweepParameter>* out) {
  if (!node.IsMap()) {
    errors->Add(Where(file, node), "'" + block + "': expected a mapping of parameters to " +
                                       (grid ? "lists of values" : "values"));
    return;
  }
  for (auto it = node.begin(); it != node.end(); ++it) {
    SweepParameter p;
    p.name = it->first.Scalar();
    p.where = Where(file, it->first);
    if (!CheckName(p.name, p.where, errors)) continue;
    bool ok = true;
    if (grid) {
      if (!it->second.IsSequence() || it->second.size() == 0) {
        errors->Add(Where(file, it->second), "grid parameter '" + p.name + "': expected a non-empty list of values");
        continue;
      }
      for (std::size_t i = 0; i < it->second.size(); ++i) {
        SweepValue v;
        ok = ReadValue(p.name, it->second[i], file, errors, &v) && ok;
        p.values.push_back(std::move(v));
      }
    } else {
      SweepValue v;
      ok = ReadValue(p.name, it->second, file, errors, &v);
      p.values.push_back(std::move(v));
    }
    if (ok) Replace(out, std::move(p));
  }
}

void ReadRandom(const YAML::Node& node, const std::string& file, ErrorList* errors, Sweep* sweep) {
  YamlMap m(node, file, "random", errors);
  if (!m.valid()) return;
  double draws = sweep->draws;
  if (m.Require("draws", &draws, InRange(1, static_cast<double>(kMaxSweepJobs)))) sweep->draws = static_cast<int>(draws);
  const YAML::Node params = m.Child("parameters");
  m.Finish();
  if (!params.IsDefined()) {
    m.Missing("parameters");
    return;
  }
  if (!params.IsMap()) {
    errors->Add(Where(file, params), "'random.parameters': expected a mapping of parameters to distributions");
    return;
  }
  for (auto it = params.begin(); it != params.end(); ++it) {
    SweepParameter p;
    p.name = it->first.Scalar();
    p.where = Where(file, it->first);
    if (!CheckName(p.name, p.where, errors)) continue;
    if (IsPathInput(p.name) || p.name == "backends") {
      errors->Add(p.where, "random parameter '" + p.name + "': draw paths and lists from a grid instead");
      continue;
    }
    const std::string context = "random.parameters." + p.name;
    if (!it->second.IsMap() || it->second.size() != 1) {
      errors->Add(Where(file, it->second), "'" + context +
                                               "': expected one distribution, e.g. {uniform: [1, 3]} (known: "
                                               "uniform, log_uniform, integer, choice)");
      continue;
    }
    p.distribution = it->second.begin()->first.Scalar();
    const YAML::Node args = it->second.begin()->second;
    if (std::find(kDistributions.begin(), kDistributions.end(), p.distribution) == kDistributions.end()) {
      errors->Add(Where(file, it->second.begin()->first),
                  "'" + context + "': unknown distribution '" + p.distribution +
                      "' (known: uniform, log_uniform, integer, choice)");
      continue;
    }
    if (!args.IsSequence() || args.size() == 0) {
      errors->Add(Where(file, args), "'" + context + "': expected a list");
      continue;
    }
    if (p.distribution == "choice") {
      bool ok = true;
      for (std::size_t i = 0; i < args.size(); ++i) {
        SweepValue v;
        ok = ReadValue(p.name, args[i], file, errors, &v) && ok;
        p.values.push_back(std::move(v));
      }
      if (ok) Replace(&sweep->random, std::move(p));
      continue;
    }
    if (args.size() != 2) {
      errors->Add(Where(file, args), "'" + context + "': expected [lo, hi]");
      continue;
    }
    const std::optional<double> lo = ReadNumber(args[0], file, context + "[0]", errors);
    const std::optional<double> hi = ReadNumber(args[1], file, context + "[1]", errors);
    if (!lo || !hi) continue;
    if (!(*lo <= *hi)) {
      errors->Add(Where(file, args), "'" + context + "': lo must not exceed hi");
      continue;
    }
    if (p.distribution == "log_uniform" && *lo <= 0) {
      errors->Add(Where(file, args), "'" + context + "': log_uniform needs lo > 0");
      continue;
    }
    if (p.distribution == "integer" && (*lo != std::floor(*lo) || *hi != std::floor(*hi))) {
      errors->Add(Where(file, args), "'" + context + "': integer needs whole numbers");
      continue;
    }
    if ((p.name == "horizon" || p.name == "seed") && (p.distribution != "integer" || *lo < 0)) {
      errors->Add(Where(file, args), "'" + context + "': draw " + p.name + " as {integer: [lo, hi]} with lo >= 0");
      continue;
    }
    p.lo = *lo;
    p.hi = *hi;
    Replace(&sweep->random, std::move(p));
  }
}

Sweep ReadSweep(const std::string& path, int depth) {
  const YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap()) throw InputError(SourceLocation{path, 1}, "expected a YAML mapping at the top level");
  Sweep sweep;
  ErrorList errors;
  YamlMap top(root, path, "", &errors);
  if (top.Has("extends")) {
    std::string base;
    const SourceLocation where = top.Where(top.Child("extends"));
    if (top.Get("extends", &base)) {
      if (depth >= 8) throw InputError(where, "'extends' nested more than 8 deep (a cycle?)");
      fs::path p(base);
      if (p.is_relative()) p = fs::path(path).parent_path() / p;
      std::error_code missing;
      if (!fs::exists(p, missing))
        throw InputError(where, "'extends': no sweep file " + p.lexically_normal().string());
      sweep = ReadSweep(p.lexically_normal().string(), depth + 1);
    }
  }
  sweep.path = path;
  if (!top.Get("name", &sweep.name) && depth == 0 && sweep.name.empty()) sweep.name = fs::path(path).stem().string();
  double seed = static_cast<double>(sweep.seed);
  if (top.Get("seed", &seed, InRange(0, 9007199254740992.0))) sweep.seed = static_cast<std::uint64_t>(seed);
  top.Get("command", &sweep.command, kCommands);
  top.Get("plots", &sweep.plots);
  if (top.Has("fixed")) ReadParameterBlock(top.Child("fixed"), path, "fixed", false, &errors, &sweep.fixed);
  if (top.Has("grid")) ReadParameterBlock(top.Child("grid"), path, "grid", true, &errors, &sweep.grid);
  if (top.Has("random")) ReadRandom(top.Child("random"), path, &errors, &sweep);
  top.Finish();
  errors.ThrowIfAny();
  return sweep;
}

// What every job of the sweep's command needs; reported at the top of the file.
void CheckCommandInputs(const Sweep& sweep, ErrorList* errors) {
  std::set<std::string> names;
  std::set<std::string> seen;
  for (const auto* list : {&sweep.fixed, &sweep.grid, &sweep.random}) {
    for (const SweepParameter& p : *list) {
      if (!seen.insert(p.name).second)
        errors->Add(p.where, "parameter '" + p.name + "' is given in more than one of fixed, grid and random");
      names.insert(p.name);
    }
  }
  const SourceLocation top{sweep.path};
  const auto has = [&](const std::string& n) { return names.count(n) > 0; };
  if (sweep.command == "run") {
    if (!has("scene")) errors->Add(top, "command run: every job needs a scene (give 'scene' in fixed or grid)");
    for (const char* n : {"model", "log", "horizon", "backends"})
      if (has(n)) errors->Add(top, std::string("command run: parameter '") + n + "' does not apply");
    for (const std::string& n : names)
      if (n.rfind("model.", 0) == 0)
        errors->Add(top, "command run: '" + n + "' sets a key of --model, which run has not; use plant." +
                             n.substr(6) + " for the scene's robot");
  } else {
    if (!has("model")) errors->Add(top, "command " + sweep.command + ": every job needs a model");
    if (!has("log") && !has("scene"))
      errors->Add(top, "command " + sweep.command +
                           ": every job needs a log, or a scene whose run records it (give 'log' or 'scene')");
    if (has("log") && has("scene"))
      errors->Add(top, "command " + sweep.command + ": give either a log or a scene that records one, not both");
    if (sweep.command == "replay" && has("backends"))
      errors->Add(top, "command replay: 'backends' applies to compare; replay takes one 'backend'");
    if (sweep.command == "compare" && (has("backend") || has("horizon")))
      errors->Add(top, "command compare: use 'backends' (a list); compare predicts at 1 frame, 4 frames, 1 s and "
                       "free run");
  }
}

}  // namespace

std::int64_t Sweep::num_jobs() const {
  std::int64_t n = std::max(draws, 1);
  for (const SweepParameter& p : grid) {
    n *= static_cast<std::int64_t>(p.values.size());
    if (n > kMaxSweepJobs) return n;
  }
  return n;
}

std::vector<std::string> Sweep::swept() const {
  std::vector<std::string> names;
  for (const SweepParameter& p : grid) names.push_back(p.name);
  for (const SweepParameter& p : random) names.push_back(p.name);
  return names;
}

const SweepValue* SweepJob::Find(const std::string& name) const {
  for (const auto& [n, v] : parameters)
    if (n == name) return &v;
  return nullptr;
}

Sweep LoadSweep(const std::string& path) {
  Sweep sweep = ReadSweep(path, 0);
  ErrorList errors;
  CheckCommandInputs(sweep, &errors);
  if (sweep.random.empty() && sweep.draws > 0)
    errors.Add(SourceLocation{path}, "'random': draws given but no parameters to draw");
  if (!sweep.random.empty() && sweep.draws == 0) errors.Add(SourceLocation{path}, "'random': missing 'draws'");
  if (sweep.num_jobs() > kMaxSweepJobs)
    errors.Add(sweep.grid.empty() ? SourceLocation{path} : sweep.grid.front().where, "the sweep holds " + std::to_string(sweep.num_jobs()) +
                                         " jobs or more; at most " + std::to_string(kMaxSweepJobs) +
                                         " fit in one sweep (split it)");
  errors.ThrowIfAny();
  return sweep;
}

std::vector<SweepJob> ExpandSweep(const Sweep& sweep) {
  const std::int64_t n = sweep.num_jobs();
  const int draws = std::max(sweep.draws, 1);
  const int width = std::max<int>(4, static_cast<int>(std::to_string(n - 1).size()));
  std::vector<SweepJob> jobs(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) {
    SweepJob& job = jobs[static_cast<std::size_t>(i)];
    job.index = static_cast<int>(i);
    job.id = std::to_string(i);
    job.id.insert(0, static_cast<std::size_t>(std::max<int>(0, width - static_cast<int>(job.id.size()))), '0');
    // One stream per job: its seed first, then its random parameters in order, so a
    // job's draws do not depend on any other job.
    Rng rng = Rng::Derived(sweep.seed, static_cast<std::uint64_t>(i));
    job.seed = static_cast<std::uint64_t>(rng.Uniform() * 2147483647.0);
    for (const SweepParameter& p : sweep.fixed) job.parameters.emplace_back(p.name, p.values.front());
    // The grid point: the first axis varies slowest.
    std::int64_t point = i / draws;
    std::vector<std::size_t> pick(sweep.grid.size());
    for (std::size_t a = sweep.grid.size(); a-- > 0;) {
      const std::int64_t size = static_cast<std::int64_t>(sweep.grid[a].values.size());
      pick[a] = static_cast<std::size_t>(point % size);
      point /= size;
    }
    for (std::size_t a = 0; a < sweep.grid.size(); ++a)
      job.parameters.emplace_back(sweep.grid[a].name, sweep.grid[a].values[pick[a]]);
    for (const SweepParameter& p : sweep.random) {
      SweepValue v;
      if (p.distribution == "choice") {
        v = p.values[static_cast<std::size_t>(rng.Index(p.values.size()))];
      } else {
        double x = 0;
        if (p.distribution == "uniform") x = rng.Uniform(p.lo, p.hi);
        if (p.distribution == "log_uniform") x = std::exp(rng.Uniform(std::log(p.lo), std::log(p.hi)));
        if (p.distribution == "integer")
          x = p.lo + static_cast<double>(rng.Index(static_cast<std::uint64_t>(p.hi - p.lo) + 1));
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.10g", x);
        v.text = buf;
        v.node = YAML::Node(v.text);
      }
      job.parameters.emplace_back(p.name, v);
    }
    if (const SweepValue* s = job.Find("seed")) job.seed = static_cast<std::uint64_t>(std::stod(s->text));
  }
  return jobs;
}

}  // namespace twinsim
