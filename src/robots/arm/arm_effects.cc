#include "robots/arm/arm_effects.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "io/yaml_reader.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_internal.h"

namespace twinsim {
namespace {

constexpr double kMaxTimeDelay = 10;  // s; longer is surely a unit mistake (ms for s)

// One parameter of an effect: its key, whether it must be given and what it may be.
struct ParameterSpec {
  const char* key;
  bool required;
  std::function<std::string(double)> check;
};

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}


// A profile's keys (position_friction, `letter` c; position_torque, p): the knots' span,
// then the levels letter1..letterK (the first two required).
std::vector<ParameterSpec> ProfileSpecs(char letter) {
  // The specs keep the keys' pointers: one table per letter, alive for the program.
  static std::map<char, std::vector<std::string>> level_keys;
  std::vector<std::string>& keys = level_keys[letter];
  if (keys.empty()) {
    for (int k = 0; k < kMaxProfileKnots; ++k) keys.push_back(ProfileLevelKey(letter, k));
  }
  std::vector<ParameterSpec> specs = {{"from", true, InRange(-1e6, 1e6)}, {"to", true, InRange(-1e6, 1e6)}};
  for (int k = 0; k < kMaxProfileKnots; ++k)
    specs.push_back({keys[static_cast<std::size_t>(k)].c_str(), k < 2, InRange(-1e7, 1e7)});
  return specs;
}

// The parameter table of the vocabulary; the order is the documentation's.
const std::vector<ParameterSpec>* SpecsOf(const std::string& name) {
  static const std::map<std::string, std::vector<ParameterSpec>> specs = {
      // Upper bounds far above any real joint, so that a typo (1e308) is caught here
      // and not as a NaN in the middle of a run.
      {"viscous_friction", {{"b", true, NonNegative(1e6)}}},
      {"coulomb_friction",
       {{"c", false, NonNegative(1e7)}, {"c_pos", false, NonNegative(1e7)}, {"c_neg", false, NonNegative(1e7)}}},
      {"position_friction", ProfileSpecs('c')},
      {"stribeck_friction",
       {{"c", true, NonNegative(1e7)},
        {"s", true, Positive(1e7)},
        {"vs", true, Positive(1e4)},
        {"sigma0", false, Positive(1e12)},
        {"sigma1", false, NonNegative(1e9)},
        {"maxwell", false, InRange(0, 1)}}},
      {"torque_offset", {{"tau0", true, InRange(-1e7, 1e7)}}},
      {"position_torque", ProfileSpecs('p')},
      {"torque_saturation", {{"limit", true, Positive(1e7)}}},
      {"time_delay", {{"delay", true, InRange(0, kMaxTimeDelay)}}},
      {"joint_flexibility",
       {{"k", true, Positive(1e9)}, {"damping", false, NonNegative(1e6)}, {"motor_inertia", true, Positive(1e3)}}},
      {"payload",
       {{"mass", true, Positive(1e5)}, {"x", false, InRange(-100, 100)}, {"y", false, InRange(-100, 100)},
        {"z", false, InRange(-100, 100)}}},
  };
  const auto it = specs.find(name);
  return it == specs.end() ? nullptr : &it->second;
}

std::string KnownNames() {
  std::string list;
  for (const std::string& n : ArmEffectNames()) list += (list.empty() ? "" : ", ") + n;
  return list;
}

std::string JointLabel(int joint) { return "joint " + std::to_string(joint + 1); }

// stribeck_friction's parameters (checked one by one) into `j`; the combination's
// problems (s <= c, bristle parameters without sigma0) into `problems`.
void ApplyStribeck(const std::map<std::string, double>& p, const std::string& label, JointEffects* j,
                   std::vector<std::string>* problems) {
  auto has = [&p](const char* key) { return p.count(key) > 0; };
  auto get = [&p](const char* key) {
    const auto it = p.find(key);
    return it == p.end() ? 0.0 : it->second;
  };
  if (!(get("s") > get("c"))) {
    problems->push_back(label + ": the static level s = " + Number(get("s")) +
                        " must exceed the sliding level c = " + Number(get("c")));
  }
  if (has("sigma1") && !has("sigma0")) {
    problems->push_back(label + ": 'sigma1' damps the bristles of 'sigma0' (LuGre): give sigma0 too");
  }
  if (has("maxwell") && !has("sigma0")) {
    problems->push_back(label + ": 'maxwell' makes the bristles of 'sigma0' a Maxwell-slip element: give sigma0 too");
  }
  if (has("maxwell") && get("maxwell") != 0 && get("maxwell") != 1) {
    problems->push_back(label + ": 'maxwell' is 1 (a Maxwell-slip element) or 0 (LuGre), not " +
                        Number(get("maxwell")));
  }
  j->stribeck_coulomb = get("c");
  j->stribeck_static = get("s");
  j->stribeck_velocity = get("vs");
  j->bristle_stiffness = get("sigma0");
  j->bristle_damping = get("sigma1");
  j->bristle_slip = get("maxwell") == 1;
}

// A profile's parameters (checked one by one, levels named `letter`1, ...) into
// `profile`; the combination's problems (to <= from, a level missing between two given)
// into `problems`.
void ApplyProfile(const std::map<std::string, double>& p, char letter, const std::string& label,
                  KnotProfile* profile, std::vector<std::string>* problems) {
  const double from = p.at("from"), to = p.at("to");
  if (!(to > from)) {
    problems->push_back(label + ": the last knot 'to' = " + Number(to) + " must lie beyond the first, 'from' = " +
                        Number(from));
  }
  const int knots = std::min(ProfileLevelCount(letter, p), kMaxProfileKnots);
  for (int k = knots + 1; k < kMaxProfileKnots; ++k) {
    if (p.count(ProfileLevelKey(letter, k)) > 0) {
      problems->push_back(label + ": '" + ProfileLevelKey(letter, k) + "' given without '" +
                          ProfileLevelKey(letter, knots) + "': the levels are " + ProfileLevelKey(letter, 0) + ", " +
                          ProfileLevelKey(letter, 1) + ", ... in order");
      break;
    }
  }
  profile->knots = knots;
  profile->from = from;
  profile->to = to;
  for (int k = 0; k < knots; ++k) profile->levels[static_cast<std::size_t>(k)] = p.at(ProfileLevelKey(letter, k));
}

// Sets `effect` (whose keys and ranges were checked) into `effects`; every problem of
// the combination (missing alternatives, s <= c, a duplicate) goes to `problems`.
void Apply(const ArmEffect& effect, int dof, ArmEffects* effects, std::vector<std::string>* problems) {
  const auto& p = effect.parameters;
  auto has = [&p](const char* key) { return p.count(key) > 0; };
  auto get = [&p](const char* key, double fallback = 0) {
    const auto it = p.find(key);
    return it == p.end() ? fallback : it->second;
  };
  const std::string label = "effect '" + effect.name + "'";
  if (effect.name == "payload") {
    if (effect.joint != -1) {
      problems->push_back(label + " acts on the last link: its joint must be null");
      return;
    }
    if (effects->payload_mass > 0) {
      problems->push_back(label + " given twice");
      return;
    }
    effects->payload_mass = get("mass");
    effects->payload_position = Eigen::Vector3d(get("x"), get("y"), get("z"));
    return;
  }
  if (effect.joint < 0 || effect.joint >= dof) {
    problems->push_back(label + " needs a joint in 1.." + std::to_string(dof) +
                        (effect.joint == -1 ? " (got null)" : " (got " + std::to_string(effect.joint + 1) + ")"));
    return;
  }
  if (effects->joints.empty()) effects->joints.assign(static_cast<std::size_t>(dof), JointEffects{});
  JointEffects& j = effects->joints[static_cast<std::size_t>(effect.joint)];
  const std::string twice = label + " given twice for " + JointLabel(effect.joint);
  if (effect.name == "viscous_friction") {
    if (j.viscous > 0) problems->push_back(twice);
    j.viscous = get("b");
  } else if (effect.name == "coulomb_friction") {
    if (j.coulomb_positive > 0 || j.coulomb_negative > 0) problems->push_back(twice);
    if (has("c") && (has("c_pos") || has("c_neg"))) {
      problems->push_back(label + ": give either 'c' or both 'c_pos' and 'c_neg'");
    } else if (has("c")) {
      j.coulomb_positive = j.coulomb_negative = get("c");
    } else if (has("c_pos") && has("c_neg")) {
      j.coulomb_positive = get("c_pos");
      j.coulomb_negative = get("c_neg");
    } else {
      problems->push_back(label + ": needs 'c' (both directions) or both 'c_pos' and 'c_neg'");
    }
  } else if (effect.name == "position_friction") {
    if (j.position_friction()) problems->push_back(twice);
    ApplyProfile(p, 'c', label, &j.friction_profile, problems);
  } else if (effect.name == "stribeck_friction") {
    if (j.stribeck()) problems->push_back(twice);
    ApplyStribeck(p, label, &j, problems);
  } else if (effect.name == "torque_offset") {
    if (j.torque_offset != 0) problems->push_back(twice);
    j.torque_offset = get("tau0");
  } else if (effect.name == "position_torque") {
    if (j.torque_profile.on()) problems->push_back(twice);
    ApplyProfile(p, 'p', label, &j.torque_profile, problems);
  } else if (effect.name == "torque_saturation") {
    if (j.saturation > 0) problems->push_back(twice);
    j.saturation = get("limit");
  } else if (effect.name == "time_delay") {
    if (j.time_delay > 0) problems->push_back(twice);
    j.time_delay = get("delay");
  } else if (effect.name == "joint_flexibility") {
    if (j.flexible()) problems->push_back(twice);
    j.stiffness = get("k");
    j.flex_damping = get("damping");
    j.motor_inertia = get("motor_inertia");
  }
}

// A profile as the effect `name` with levels `letter`1.. lists it.
ArmEffect ProfileEffect(const char* name, char letter, int joint, const KnotProfile& profile) {
  ArmEffect effect{name, joint, {{"from", profile.from}, {"to", profile.to}}};
  for (int k = 0; k < profile.knots; ++k)
    effect.parameters[ProfileLevelKey(letter, k)] = profile.levels[static_cast<std::size_t>(k)];
  return effect;
}

void ThrowProblems(const std::vector<std::string>& problems) {
  ErrorList errors;
  for (const std::string& p : problems) errors.Add(p);
  errors.ThrowIfAny();
}

}  // namespace

std::string ProfileLevelKey(char letter, int k) { return letter + std::to_string(k + 1); }

int ProfileLevelCount(char letter, const std::map<std::string, double>& parameters) {
  int levels = 0;
  while (parameters.count(ProfileLevelKey(letter, levels)) > 0) ++levels;
  return levels;
}

bool ArmEffects::any() const { return payload_mass > 0 || !ListArmEffects(*this).empty(); }

const std::vector<std::string>& ArmEffectNames() {
  static const std::vector<std::string> names = {"viscous_friction",  "coulomb_friction", "stribeck_friction",
                                                 "torque_offset",     "torque_saturation", "time_delay",
                                                 "joint_flexibility", "payload",          "position_friction",
                                                 "position_torque"};
  return names;
}

std::vector<std::string> ArmEffectParameters(const std::string& name) {
  std::vector<std::string> keys;
  if (const auto* specs = SpecsOf(name)) {
    for (const ParameterSpec& s : *specs) keys.push_back(s.key);
  }
  return keys;
}

void AddArmEffect(const ArmEffect& effect, int dof, ArmEffects* effects) {
  const auto* specs = SpecsOf(effect.name);
  if (specs == nullptr) throw InputError("unknown arm effect '" + effect.name + "' (known: " + KnownNames() + ")");
  std::vector<std::string> problems;
  const std::string label = "effect '" + effect.name + "'";
  std::string known;
  for (const ParameterSpec& s : *specs) known += (known.empty() ? "" : ", ") + std::string(s.key);
  for (const auto& [key, value] : effect.parameters) {
    const ParameterSpec* spec = nullptr;
    for (const ParameterSpec& s : *specs) {
      if (key == s.key) spec = &s;
    }
    if (spec == nullptr) {
      problems.push_back(label + ": unknown parameter '" + key + "' (known: " + known + ")");
    } else if (const std::string bad = spec->check(value); !bad.empty()) {
      problems.push_back(label + ": '" + key + "' " + bad);
    }
  }
  for (const ParameterSpec& s : *specs) {
    if (s.required && effect.parameters.count(s.key) == 0) {
      problems.push_back(label + ": missing parameter '" + std::string(s.key) + "'");
    }
  }
  if (problems.empty()) {
    ArmEffects updated = *effects;
    Apply(effect, dof, &updated, &problems);
    if (problems.empty()) *effects = updated;
  }
  ThrowProblems(problems);
}

std::vector<ArmEffect> ListArmEffects(const ArmEffects& effects) {
  std::vector<ArmEffect> out;
  for (int i = 0; i < static_cast<int>(effects.joints.size()); ++i) {
    const JointEffects& j = effects.joints[static_cast<std::size_t>(i)];
    if (j.viscous > 0) out.push_back({"viscous_friction", i, {{"b", j.viscous}}});
    if (j.coulomb_positive > 0 || j.coulomb_negative > 0) {
      if (j.coulomb_positive == j.coulomb_negative) {
        out.push_back({"coulomb_friction", i, {{"c", j.coulomb_positive}}});
      } else {
        out.push_back({"coulomb_friction", i, {{"c_pos", j.coulomb_positive}, {"c_neg", j.coulomb_negative}}});
      }
    }
    if (j.position_friction()) out.push_back(ProfileEffect("position_friction", 'c', i, j.friction_profile));
    if (j.stribeck()) {
      ArmEffect stribeck{"stribeck_friction", i,
                         {{"c", j.stribeck_coulomb}, {"s", j.stribeck_static}, {"vs", j.stribeck_velocity}}};
      if (j.presliding()) {
        stribeck.parameters["sigma0"] = j.bristle_stiffness;
        stribeck.parameters["sigma1"] = j.bristle_damping;
        if (j.bristle_slip) stribeck.parameters["maxwell"] = 1;
      }
      out.push_back(stribeck);
    }
    if (j.torque_offset != 0) out.push_back({"torque_offset", i, {{"tau0", j.torque_offset}}});
    if (j.torque_profile.on()) out.push_back(ProfileEffect("position_torque", 'p', i, j.torque_profile));
    if (j.saturation > 0) out.push_back({"torque_saturation", i, {{"limit", j.saturation}}});
    if (j.time_delay > 0) out.push_back({"time_delay", i, {{"delay", j.time_delay}}});
    if (j.flexible()) {
      out.push_back({"joint_flexibility", i,
                     {{"k", j.stiffness}, {"damping", j.flex_damping}, {"motor_inertia", j.motor_inertia}}});
    }
  }
  if (effects.payload_mass > 0) {
    const Eigen::Vector3d& p = effects.payload_position;
    out.push_back({"payload", -1, {{"mass", effects.payload_mass}, {"x", p.x()}, {"y", p.y()}, {"z", p.z()}}});
  }
  return out;
}

void ReadArmEffects(const YAML::Node& list, const std::string& path, ArmModel* model, ErrorList* errors) {
  auto where = [&path](const YAML::Node& node) {
    return SourceLocation{path, node.Mark().line + 1, node.Mark().column + 1};
  };
  if (!list.IsSequence()) {
    errors->Add(where(list), "'effects': expected a list of effects, each with a 'name'");
    return;
  }
  const int dof = model->dof();
  for (std::size_t k = 0; k < list.size(); ++k) {
    const YAML::Node node = list[k];
    const std::string context = "effect " + std::to_string(k + 1);
    YamlMap m(node, path, context, errors);
    if (!m.valid()) continue;
    ArmEffect effect;
    // Without a usable name its keys cannot be checked: report only the name.
    if (!m.Require("name", &effect.name, ArmEffectNames())) continue;
    bool ok = true;
    // joint: null, a 1-based number or a joint's name.
    if (m.Has("joint")) {
      const YAML::Node j = m.Child("joint");
      if (j.IsNull()) {
        effect.joint = -1;
      } else if (!j.IsScalar()) {
        m.Error("joint", "expected a joint number (1.." + std::to_string(dof) + "), a joint name or null");
        ok = false;
      } else {
        int index = -1;
        for (int i = 0; i < dof; ++i) {
          if (model->joints[static_cast<std::size_t>(i)].name == j.Scalar()) index = i;
        }
        if (index < 0) {
          try {
            std::size_t used = 0;
            const int number = std::stoi(j.Scalar(), &used);
            if (used == j.Scalar().size() && number >= 1 && number <= dof) index = number - 1;
          } catch (const std::exception&) {
          }
        }
        if (index < 0) {
          std::string names;
          for (const ArmJoint& aj : model->joints) names += (names.empty() ? "" : ", ") + aj.name;
          m.Error("joint", "no joint '" + j.Scalar() + "' (known: 1.." + std::to_string(dof) + " or " + names + ")");
          ok = false;
        }
        effect.joint = index;
      }
    } else if (effect.name != "payload") {
      m.Missing("joint");
      ok = false;
    }
    for (const ParameterSpec& s : *SpecsOf(effect.name)) {
      double value = 0;
      if (s.required && !m.Has(s.key)) {
        m.Missing(s.key);
        ok = false;
      } else if (m.Has(s.key)) {
        if (m.Get(s.key, &value, s.check)) {
          effect.parameters[s.key] = value;
        } else {
          ok = false;
        }
      }
    }
    m.Finish();
    if (!ok) continue;
    std::vector<std::string> problems;
    Apply(effect, dof, &model->effects, &problems);
    for (const std::string& p : problems) errors->Add(where(node), context + ": " + p);
  }
}

namespace {

// ArmDryFrictionLevel and ArmFrictionTorque of a joint `nominal` with effects `e` (the
// replay calls them for every row of a log).
double DryFrictionLevel(const ArmJoint& nominal, const JointEffects& e, double q, double qd) {
  return e.SlidingLevel(nominal.coulomb, q, std::abs(qd), qd >= 0 ? 1 : -1);
}

double FrictionTorque(const ArmJoint& nominal, const JointEffects& e, double q, double qd) {
  if (qd == 0) return 0;
  const double level = DryFrictionLevel(nominal, e, q, qd);
  return (nominal.viscous + e.viscous) * qd + (qd > 0 ? level : -level);
}

// ArmBristleStepFrom and ArmMaxwellSlipLevels of a joint `nominal` with effects `e`.
ArmBristleStep BristleStepFrom(const ArmJoint& nominal, const JointEffects& e, double q, double z0, double qd0,
                               double h) {
  const double g = DryFrictionLevel(nominal, e, q, qd0);
  // With v(t) = qd0 + (qd1 - qd0) t / h: z(h) = z0 E + qd0 P + (qd1 - qd0) Q, where
  // E = exp(-a h), P = (1 - E) / a and Q = (h - P) / (a h) (h and h / 2 as a -> 0).
  const double a = g > 0 && !e.bristle_slip ? e.bristle_stiffness * std::abs(qd0) / g : 0;
  const double ah = a * h;
  if (ah < 1e-8) return {z0 + 0.5 * h * qd0, 0.5 * h};
  const double p = -std::expm1(-ah) / a;
  const double r = (h - p) / ah;  // the comment's Q
  return {z0 * std::exp(-ah) + qd0 * (p - r), r};
}

ArmSlipLevels MaxwellSlipLevels(const ArmJoint& nominal, const JointEffects& e, double q, double qd0) {
  constexpr double kTinySpeed = 1e-300;  // a speed that only gives a direction
  const double speed = std::abs(qd0);
  return {DryFrictionLevel(nominal, e, q, speed), DryFrictionLevel(nominal, e, q, -std::max(speed, kTinySpeed))};
}

}  // namespace

double ArmDryFrictionLevel(const ArmModel& model, int joint, double q, double qd) {
  return DryFrictionLevel(model.joints.at(static_cast<std::size_t>(joint)), model.effects.joint(joint), q, qd);
}

double ArmFrictionTorque(const ArmModel& model, int joint, double q, double qd) {
  return FrictionTorque(model.joints.at(static_cast<std::size_t>(joint)), model.effects.joint(joint), q, qd);
}

ArmBristleStep ArmBristleStepFrom(const ArmModel& model, int joint, double q, double z0, double qd0, double h) {
  return BristleStepFrom(model.joints.at(static_cast<std::size_t>(joint)), model.effects.joint(joint), q, z0, qd0,
                         h);
}

ArmSlipLevels ArmMaxwellSlipLevels(const ArmModel& model, int joint, double q, double qd0) {
  return MaxwellSlipLevels(model.joints.at(static_cast<std::size_t>(joint)), model.effects.joint(joint), q, qd0);
}

double ArmMaxwellSlipDeflection(const JointEffects& effects, double level, double z0, double h) {
  return (level + effects.bristle_damping * z0 / h) / (effects.bristle_stiffness + effects.bristle_damping / h);
}

Eigen::VectorXd ArmFrictionAlong(const ArmModel& model, int joint, const Eigen::VectorXd& t, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& qd) {
  const long n = qd.size();
  if (q.size() != n) throw std::invalid_argument("ArmFrictionAlong: q and qd differ in length");
  Eigen::VectorXd out(n);
  const JointEffects e = model.effects.joint(joint);
  const ArmJoint& nominal = model.joints.at(static_cast<std::size_t>(joint));
  if (!e.presliding() || !e.stribeck() || n < 2 || t.size() != n) {
    for (long r = 0; r < n; ++r) out[r] = FrictionTorque(nominal, e, q[r], qd[r]);
    return out;
  }
  const double viscous = nominal.viscous + e.viscous;
  const double s0 = e.bristle_stiffness, s1 = e.bristle_damping;
  // At the first row: the steady deflection of its velocity, whose force is the level
  // (unloaded at rest: the log does not say what holds it).
  double z = qd[0] != 0 ? std::copysign(DryFrictionLevel(nominal, e, q[0], qd[0]), qd[0]) / s0 : 0;
  for (long r = 0; r < n; ++r) {
    // Row r's friction is the step's from row r to r + 1, as the simulation logs a row
    // (its state before the step, the command acting over it); the last row's, the step
    // before it again at a held velocity.
    const double h = r + 1 < n ? t[r + 1] - t[r] : t[r] - t[r - 1];
    const double next = r + 1 < n ? qd[r + 1] : qd[r];
    const double z0 = z;
    z = BristleStepFrom(nominal, e, q[r], z0, qd[r], h).At(next);
    double dry = s0 * z + s1 * (z - z0) / h;
    if (e.bristle_slip) {
      // Beyond the dry level (the step's start speed, either way) the element slips
      // carrying exactly that level.
      const double level = MaxwellSlipLevels(nominal, e, q[r], qd[r]).For(dry);
      if (std::abs(dry) > std::abs(level)) {
        z = ArmMaxwellSlipDeflection(e, level, z0, h);
        dry = level;
      }
    }
    out[r] = dry + 0.5 * viscous * (qd[r] + next);  // viscous over the step, trapezoidal as the simulation's
  }
  return out;
}

ArmModel ArmPlantModel(const ArmModel& model) {
  ArmModel plant = model;
  if (model.effects.payload_mass > 0 && model.dof() > 0) {
    ArmLink point;
    point.name = "payload";
    point.mass = model.effects.payload_mass;
    point.com = model.effects.payload_position;
    arm_internal::AddBody(&plant.joints.back().child, point);
    plant.effects.payload_mass = 0;
  }
  return plant;
}

}  // namespace twinsim
