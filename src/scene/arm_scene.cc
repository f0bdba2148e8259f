#include "scene/arm_scene.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/engine_names.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "io/input_file.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "render/plot_spec.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kPlotTypes = {"tool_path", "joint_torques", "tracking_error"};
const std::vector<std::string> kTaskTypes = {"writing", "hold", "step", "sinusoid", "random"};

// Loads the arm model at `key` of `m` into *model (resolved path into *path).
bool ReadModel(YamlMap& m, const std::string& key, bool required, const fs::path& base_dir, std::string* path,
               ArmModel* model, const YamlOverrides& overrides = {}) {
  std::string file;
  if (!(required ? m.Require(key, &file) : m.Get(key, &file))) return false;
  *path = ResolveRelativeTo(file, base_dir.string());
  try {
    *model = LoadArmModel(*path, overrides);
    return true;
  } catch (const InputError& e) {
    m.errors()->Add(e.what());
  }
  return false;
}

bool ReadJointVector(YamlMap& m, const std::string& key, int dof, bool required, Eigen::VectorXd* out) {
  std::vector<double> v;
  if (required && !m.Has(key)) {
    m.Missing(key);
    return false;
  }
  if (!m.Get(key, &v, dof)) return false;
  *out = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  return true;
}

// Positions within the plant's joint limits.
void CheckWithinLimits(YamlMap& m, const std::string& key, const ArmModel& plant, const Eigen::VectorXd& q) {
  for (int j = 0; j < plant.dof() && j < q.size(); ++j) {
    const ArmJoint& joint = plant.joints[static_cast<std::size_t>(j)];
    if (q[j] < joint.lower || q[j] > joint.upper) {
      m.Error(key, "joint " + std::to_string(j + 1) + " ('" + joint.name + "') at " + std::to_string(q[j]) +
                       " is beyond its limits [" + std::to_string(joint.lower) + ", " + std::to_string(joint.upper) +
                       "]");
    }
  }
}

std::string FormatSeconds(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The most samples one task runs (2.8 h at 1 kHz): every sample is kept for the CSVs.
constexpr double kMaxArmSamples = 1e7;

// A task's duration: at least `least` seconds, at most a day and kMaxArmSamples samples
// of the plant's controller.
NumberCheck DurationCheck(double least, const ArmModel& plant) {
  const double ts = plant.sample_time;
  return [least, ts](double v) -> std::string {
    std::string problem = InRange(least, 24 * 3600)(v);
    if (problem.empty() && ts > 0 && v / ts > kMaxArmSamples) {
      std::ostringstream msg;
      msg << "is " << v / ts << " samples of " << ts << " s; at most " << kMaxArmSamples << " are run";
      problem = msg.str();
    }
    return problem;
  };
}

void ReadTask(const YAML::Node& node, const std::string& path, const ArmModel& plant, bool models_ok,
              ErrorList* errors, ArmTaskSpec* task) {
  YamlMap m(node, path, "task", errors);
  if (!m.valid()) return;
  m.Get("type", &task->type, kTaskTypes);
  std::vector<double> tool;
  if (m.Get("tool", &tool, 3)) task->writing.tool = Eigen::Vector3d(tool[0], tool[1], tool[2]);
  if (task->type == "writing") {
    WritingTaskOptions& w = task->writing;
    if (m.Get("letters", &w.letters)) {
      for (char c : w.letters) {
        if (WritingTaskLetters().find(c) == std::string::npos) {
          m.Error("letters", std::string("no strokes for '") + c + "' (known: \"" + WritingTaskLetters() + "\")");
          break;
        }
      }
    }
    m.Get("height", &w.height, Positive());
    m.Get("width_ratio", &w.width_ratio, Positive());
    m.Get("gap_ratio", &w.gap_ratio, NonNegative());
    m.Get("plane_x", &w.plane_x);
    m.Get("center_y", &w.center_y);
    m.Get("center_z", &w.center_z);
    m.Get("speed", &w.speed, Positive());
    m.Get("acceleration", &w.acceleration, Positive());
    m.Get("hold_before", &w.hold_before, NonNegative());
    m.Get("hold_after", &w.hold_after, NonNegative());
    std::string why;
    if (!w.IsValid(&why)) m.Error("type", "writing task: " + why);
  } else if (task->type == "random") {
    TrainingTrialOptions& r = task->training;
    m.Get("motion", &task->motion, {"multisine", "stop_and_go"});
    m.Get("duration", &r.seconds, DurationCheck(0.1, plant));
    m.Get("fundamental", &r.fundamental, Positive());
    m.Get("harmonics", &r.harmonics, InRange(1, 1000));
    m.Get("stroke_speed", &r.stroke_speed, Positive());
    m.Get("stroke_acceleration", &r.stroke_acceleration, Positive());
    if (models_ok) {
      if (ReadJointVector(m, "center", plant.dof(), false, &r.center)) CheckWithinLimits(m, "center", plant, r.center);
      ReadJointVector(m, "amplitude", plant.dof(), false, &r.amplitude);
      if (r.center.size() == 0 && plant.dof() != 3) m.Missing("center");
      if (r.amplitude.size() == 0 && plant.dof() != 3) m.Missing("amplitude");
    } else {
      for (const char* key : {"center", "amplitude"}) m.Child(key);
    }
    std::string why;
    if (!r.IsValid(&why)) m.Error("type", "random task: " + why);
  } else {
    const int dof = plant.dof();
    m.Require("duration", &task->duration, DurationCheck(1e-3, plant));
    if (models_ok) {
      if (ReadJointVector(m, "q", dof, true, &task->q)) CheckWithinLimits(m, "q", plant, task->q);
      if (task->type == "step") {
        if (ReadJointVector(m, "to", dof, true, &task->to)) CheckWithinLimits(m, "to", plant, task->to);
        m.Get("at", &task->at, NonNegative());
      } else if (task->type == "sinusoid") {
        if (ReadJointVector(m, "amplitude", dof, true, &task->amplitude) && task->q.size() == dof) {
          CheckWithinLimits(m, "amplitude", plant, task->q + task->amplitude.cwiseAbs());
          CheckWithinLimits(m, "amplitude", plant, task->q - task->amplitude.cwiseAbs());
        }
        m.Get("frequency", &task->frequency, Positive());
      }
    } else {
      // Without the models the joint count is unknown: only mark the keys as known.
      for (const char* key : {"q", "to", "at", "amplitude", "frequency"}) m.Child(key);
    }
  }
  m.Finish();
}

std::vector<ArmPlotSpec> ReadArmPlots(YamlMap& top) {
  std::vector<ArmPlotSpec> specs;
  const YAML::Node list = top.Child("plots");
  if (!list.IsDefined() || list.IsNull()) return specs;
  if (!list.IsSequence()) {
    top.Error("plots", "expected a list of plots, e.g. [{type: tool_path, file: path.png}]");
    return specs;
  }
  std::set<std::string> files;
  for (std::size_t i = 0; i < list.size(); ++i) {
    YamlMap m(list[i], top.path(), "plots[" + std::to_string(i) + "]", top.errors());
    if (!m.valid()) continue;
    ArmPlotSpec spec;
    bool ok = m.Require("type", &spec.type, kPlotTypes);
    ok = ReadPlotFile(m, &files, &spec.file) && ok;
    m.Get("width", &spec.width, InRange(240, 8192));
    m.Get("height", &spec.height, InRange(180, 8192));
    m.Get("title", &spec.title);
    m.Finish();
    if (ok) specs.push_back(spec);
  }
  return specs;
}

// The `ilc:` block (IlcSpec).
void ReadIlc(const YAML::Node& node, const std::string& path, const ArmModel& plant, bool models_ok,
             ErrorList* errors, IlcSpec* ilc) {
  YamlMap m(node, path, "ilc", errors);
  if (!m.valid()) return;
  ilc->present = true;
  IlcOptions& o = ilc->options;
  m.Get("trials", &o.trials, InRange(0, 1000));
  m.Get("gain", &o.gain, InRange(1e-6, 2));
  m.Get("learning_filter", &ilc->learning_filter, {"fitted", "model"});
  m.Get("update", &o.update, {"standard", "norm_optimal"});
  m.Get("q_criterion", &o.q_criterion, {"lines", "robust"});
  m.Get("norm_optimal_bandwidth", &o.norm_optimal_bandwidth, NonNegative(1e6));
  m.Get("q_order", &o.q_order, InRange(0, 16));
  const YAML::Node cutoff = m.Has("q_cutoff") ? m.Child("q_cutoff") : YAML::Node();
  if (cutoff.IsDefined() && cutoff.IsScalar() && cutoff.Scalar() == "auto") {
    ilc->q_cutoff_auto = true;
  } else if (cutoff.IsDefined()) {
    ilc->q_cutoff_auto = false;
    if (m.Get("q_cutoff", &o.q_cutoff, Positive()) && plant.sample_time > 0 && o.q_cutoff >= 0.5 / plant.sample_time) {
      std::ostringstream msg;
      msg << "must lie below the Nyquist frequency " << 0.5 / plant.sample_time << " Hz";
      m.Error("q_cutoff", msg.str());
    }
  }
  const bool has_guard = m.Has("safeguard");
  const YAML::Node guard = has_guard ? m.Child("safeguard") : YAML::Node();
  if (has_guard && guard.IsScalar() && guard.Scalar() == "off") {
    o.safeguard.growth = 0;
  } else if (has_guard) {
    YamlMap g(guard, path, "ilc.safeguard", errors);
    if (g.valid()) {
      if (g.Get("growth", &o.safeguard.growth) && !(o.safeguard.growth > 1)) g.Error("growth", "must be > 1 (or the whole key `off`)");
      if (g.Get("cutoff_factor", &o.safeguard.cutoff_factor) &&
          !(o.safeguard.cutoff_factor > 0 && o.safeguard.cutoff_factor < 1)) {
        g.Error("cutoff_factor", "must lie between 0 and 1 (exclusive)");
      }
      g.Get("min_cutoff", &o.safeguard.min_cutoff, Positive());
      g.Get("patience", &o.safeguard.patience, InRange(1, 1000));
      g.Get("lowerings", &o.safeguard.lowerings, InRange(0, 100));
      g.Finish();
    }
  }
  if (m.Has("frf")) {
    YamlMap f(m.Child("frf"), path, "ilc.frf", errors);
    if (f.valid()) {
      FrfOptions& frf = ilc->frf;
      f.Get("period", &frf.period, InRange(1e-3, 3600));
      f.Get("periods", &frf.periods, InRange(1, 1000));
      f.Get("amplitude", &frf.amplitude, InRange(1e-6, 1));
      std::vector<double> band;
      if (f.Get("band", &band, 2, Positive())) {
        if (band[1] <= band[0]) {
          f.Error("band", "expected [low, high] Hz with low < high");
        } else {
          frf.f_min = band[0], frf.f_max = band[1];
        }
      }
      if (f.Get("fit_band", &band, 2, Positive())) {
        if (band[1] <= band[0]) {
          f.Error("fit_band", "expected [low, high] Hz with low < high");
        } else {
          ilc->fit.f_min = band[0], ilc->fit.f_max = band[1];
        }
      }
      f.Get("max_shift", &ilc->fit.max_shift, InRange(0, 100));
      f.Get("coherence", &ilc->fit.min_coherence, InRange(0, 1));
      if (f.Get("model_order", &ilc->fit.order) && ilc->fit.order != 2 && ilc->fit.order != 4) {
        f.Error("model_order", "must be 2 (rigid: inertia and delay) or 4 (with a series spring)");
      }
      const YAML::Node list = f.Child("postures");
      if (list.IsDefined() && !list.IsNull()) {
        if (!list.IsSequence() || list.size() == 0) {
          f.Error("postures", "expected a list of joint positions, e.g. [[0, 0.6, -1.7], [0.3, 0.9, -1.5]]");
        } else if (models_ok) {
          for (std::size_t i = 0; i < list.size(); ++i) {
            const YAML::Node item = list[i];
            const SourceLocation where = f.Where(item);
            if (!item.IsSequence() || static_cast<int>(item.size()) != plant.dof()) {
              errors->Add(where, "'ilc.frf.postures[" + std::to_string(i) + "]': expected " +
                                     std::to_string(plant.dof()) + " joint positions");
              continue;
            }
            Eigen::VectorXd q(plant.dof());
            bool ok = true;
            for (int j = 0; j < plant.dof(); ++j) {
              const auto v = ReadNumber(item[static_cast<std::size_t>(j)], path,
                                        "ilc.frf.postures[" + std::to_string(i) + "]", errors);
              ok = ok && v.has_value();
              if (v) q[j] = *v;
            }
            if (!ok) continue;
            for (int j = 0; j < plant.dof(); ++j) {
              const ArmJoint& joint = plant.joints[static_cast<std::size_t>(j)];
              if (q[j] < joint.lower || q[j] > joint.upper) {
                errors->Add(where, "'ilc.frf.postures[" + std::to_string(i) + "]': joint " + std::to_string(j + 1) +
                                       " ('" + joint.name + "') is beyond its limits");
                ok = false;
              }
            }
            if (ok) ilc->postures.push_back(q);
          }
        }
      }
      std::string why;
      if (!frf.IsValid(&why)) f.Error("band", why);
      f.Finish();
    }
  }
  m.Finish();
}

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A count per revolution: a whole number, 0 (exact) up to what a 30-bit encoder gives.
NumberCheck CountsPerRev() {
  return [](double v) {
    if (v < 0 || v > 1e9) return InRange(0, 1e9)(v);
    return v == std::floor(v) ? std::string() : "expected a whole number of counts, got " + Number(v);
  };
}

// A linear encoder's step: 0 (exact) or between 1 nm (the log's 9 decimals) and 1 m.
NumberCheck LinearResolution() {
  return [](double v) {
    return v == 0 || (v >= 1e-9 && v <= 1) ? std::string()
                                           : "must be 0 (exact) or in [1e-9, 1] m, got " + Number(v);
  };
}

// `key` of `m` as one value per joint: a number for every joint or a list of `dof`
// numbers. Leaves *out unchanged (and returns false) when absent or invalid; *listed
// tells which form was given.
bool ReadPerJoint(YamlMap& m, const std::string& key, int dof, const NumberCheck& check, Eigen::VectorXd* out,
                  bool* listed) {
  const YAML::Node node = m.Child(key);
  if (!node.IsDefined() || node.IsNull()) return false;
  *listed = node.IsSequence();
  if (*listed) {
    std::vector<double> v;
    if (!m.Get(key, &v, dof, check)) return false;
    *out = Eigen::Map<const Eigen::VectorXd>(v.data(), dof);
    return true;
  }
  if (!node.IsScalar()) {
    m.Error(key, "expected a number or a list of " + std::to_string(dof) + " numbers (one per joint)");
    return false;
  }
  double v = 0;
  if (!m.Get(key, &v, check)) return false;
  *out = Eigen::VectorXd::Constant(dof, v);
  return true;
}

// The `sensors:` block (ArmSensorSpec): revolute joints are quantised by
// encoder_counts_per_rev, prismatic ones by encoder_resolution (m). A single number
// applies to every joint of its kind; in a list, the other kind's entries must be 0.
void ReadSensors(const YAML::Node& node, const std::string& path, const ArmModel& plant, bool models_ok,
                 ErrorList* errors, ArmSensorSpec* sensors) {
  YamlMap m(node, path, "sensors", errors);
  if (!m.valid()) return;
  m.Get("log_velocities", &sensors->log_velocities);
  if (!models_ok) {
    // Without the plant the joint count and kinds are unknown: only mark the keys as known.
    for (const char* key : {"encoder_counts_per_rev", "encoder_resolution", "torque_noise"}) m.Child(key);
    m.Finish();
    return;
  }
  const int dof = plant.dof();
  auto is_revolute = [&](int j) { return plant.joints[static_cast<std::size_t>(j)].type == JointType::kRevolute; };
  // Reports entries of a list given for joints of the other kind (`other_key` is theirs),
  // and a single number for an arm without joints of this kind.
  auto check_kind = [&](const std::string& key, const Eigen::VectorXd& v, bool listed, bool revolute,
                        const std::string& other_key) {
    const YAML::Node list = m.Child(key);
    bool any_of_kind = false, ok = true;
    for (int j = 0; j < dof; ++j) {
      if (is_revolute(j) == revolute) {
        any_of_kind = true;
      } else if (listed && v[j] != 0) {
        const ArmJoint& joint = plant.joints[static_cast<std::size_t>(j)];
        errors->Add(m.Where(list[static_cast<std::size_t>(j)]),
                    "'" + key + "[" + std::to_string(j) + "]' in 'sensors': joint " + std::to_string(j + 1) + " ('" +
                        joint.name + "') is " + (revolute ? "prismatic" : "revolute") + ": its encoder is given by " +
                        other_key + "; give 0 here");
        ok = false;
      }
    }
    if (!listed && !any_of_kind && v.size() > 0 && v[0] != 0) {
      m.Error(key, "'" + plant.name + "' has no " + (revolute ? "revolute" : "prismatic") + " joint; its " +
                       (revolute ? "prismatic" : "revolute") + " joints take " + other_key);
      ok = false;
    }
    return ok;
  };

  Eigen::VectorXd counts = Eigen::VectorXd::Zero(dof), resolution = Eigen::VectorXd::Zero(dof);
  bool listed = false;
  const bool counts_ok = ReadPerJoint(m, "encoder_counts_per_rev", dof, CountsPerRev(), &counts, &listed) &&
                         check_kind("encoder_counts_per_rev", counts, listed, true, "encoder_resolution (m per count)");
  const bool resolution_ok = ReadPerJoint(m, "encoder_resolution", dof, LinearResolution(), &resolution, &listed) &&
                             check_kind("encoder_resolution", resolution, listed, false, "encoder_counts_per_rev");
  if (counts_ok || resolution_ok) {
    sensors->count_step = Eigen::VectorXd::Zero(dof);
    for (int j = 0; j < dof; ++j) {
      if (is_revolute(j)) {
        if (counts_ok && counts[j] > 0) sensors->count_step[j] = 2 * kPi / counts[j];
      } else if (resolution_ok) {
        sensors->count_step[j] = resolution[j];
      }
    }
  }
  Eigen::VectorXd noise;
  if (ReadPerJoint(m, "torque_noise", dof, NonNegative(), &noise, &listed)) sensors->torque_noise = noise;
  m.Finish();
}

ArmScene ReadArmScene(const YAML::Node& root, const std::string& path, const fs::path& base_dir,
                      const YamlOverrides& plant = {}) {
  ErrorList errors;
  ArmScene scene;
  scene.path = path;
  YamlMap top(root, path, "", &errors);
  top.Require("name", &scene.name);
  std::string robot;
  top.Require("robot", &robot, std::vector<std::string>{"arm"});
  top.Get("backend", &scene.backend, KnownBackends());
  double seed = 1;
  if (top.Get("seed", &seed, InRange(0, 9007199254740992.0))) scene.seed = static_cast<std::uint64_t>(seed);

  bool models_ok = ReadModel(top, "model", true, base_dir, &scene.plant_path, &scene.plant, plant);
  scene.hat_path = scene.plant_path;
  scene.hat = scene.plant;
  // The controller's model is the plant's file as written, never the varied plant.
  if (models_ok && !plant.empty()) models_ok = ReadModel(top, "model", true, base_dir, &scene.hat_path, &scene.hat);

  if (top.Has("controller")) {
    YamlMap c(top.Child("controller"), path, "controller", &errors);
    if (c.valid()) {
      std::string type = TrackingControllerName(scene.tracking.controller);
      if (c.Get("type", &type, {"computed_torque", "pd_feedforward"})) {
        scene.tracking.controller =
            type == "computed_torque" ? TrackingController::kComputedTorque : TrackingController::kPdFeedforward;
      }
      if (c.Has("model")) models_ok = ReadModel(c, "model", false, base_dir, &scene.hat_path, &scene.hat) && models_ok;
      c.Get("bandwidth", &scene.tracking.bandwidth, Positive());
      c.Get("damping", &scene.tracking.damping, Positive());
      c.Get("preview", &scene.tracking.preview, InRange(-1, 1000000));
      c.Get("friction", &scene.tracking.friction);
      c.Get("friction_from_reference", &scene.tracking.friction_from_reference);
      c.Get("interval_acceleration", &scene.tracking.interval_acceleration);
      c.Get("saturate", &scene.tracking.saturate);
      c.Get("dither", &scene.tracking.dither, InRange(0, 1));
      c.Get("dither_hold", &scene.tracking.dither_hold, InRange(1, 1000000));
      c.Finish();
    }
  }

  if (models_ok) {
    if (scene.hat.dof() != scene.plant.dof()) {
      top.Error("controller", "the controller's model '" + scene.hat.name + "' has " + std::to_string(scene.hat.dof()) +
                                  " joints but the plant '" + scene.plant.name + "' has " +
                                  std::to_string(scene.plant.dof()));
      models_ok = false;
    } else if (std::abs(scene.hat.sample_time - scene.plant.sample_time) > 1e-12 * scene.plant.sample_time) {
      top.Error("controller", "the controller's model samples every " + FormatSeconds(scene.hat.sample_time) +
                                  " s but the plant every " + FormatSeconds(scene.plant.sample_time) +
                                  " s; they must agree");
    }
  }

  if (top.Has("task")) {
    ReadTask(top.Child("task"), path, scene.plant, models_ok, &errors, &scene.task);
  } else {
    top.Missing("task");
  }
  scene.plots = ReadArmPlots(top);
  if (top.Has("ilc")) ReadIlc(top.Child("ilc"), path, scene.plant, models_ok, &errors, &scene.ilc);
  scene.ilc.frf.seed = scene.seed;
  if (top.Has("sensors")) ReadSensors(top.Child("sensors"), path, scene.plant, models_ok, &errors, &scene.sensors);
  top.Finish();
  errors.ThrowIfAny();
  return scene;
}

}  // namespace

RobotKind SceneRobotKind(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap() || !root["robot"]) return RobotKind::kOmni;
  const YAML::Node robot = root["robot"];
  return ParseRobotKind(robot, {path, robot.Mark().line + 1, robot.Mark().column + 1}, "a scene");
}

ArmScene LoadArmScene(const std::string& path) { return LoadArmScene(path, SceneOverrides{}); }

ArmScene LoadArmScene(const std::string& path, const SceneOverrides& overrides) {
  YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap()) throw InputError(SourceLocation{path, 1}, "expected a YAML mapping at the top level");
  if (!overrides.scene.empty()) root = ApplyYamlOverrides(root, overrides.scene, path);
  return ReadArmScene(root, path, fs::path(path).parent_path(), overrides.plant);
}

ArmScene LoadArmSceneFromString(const std::string& yaml, const std::string& name, const std::string& base_dir) {
  const YAML::Node root = LoadYamlString(yaml, name);
  if (!root.IsMap()) throw InputError(SourceLocation{name, 1}, "expected a YAML mapping at the top level");
  return ReadArmScene(root, name, base_dir);
}

namespace {

// The tool point's path (p, pd, pdd) along the joint reference, for the plots.
void FillToolPath(const ArmModel& hat, const Eigen::Vector3d& tool, ArmReference* ref) {
  const Eigen::Index samples = ref->q.rows();
  ref->p.resize(samples, 3), ref->pd.resize(samples, 3), ref->pdd.resize(samples, 3);
  for (Eigen::Index k = 0; k < samples; ++k) {
    const Eigen::VectorXd q = ref->q.row(k).transpose(), qd = ref->qd.row(k).transpose(),
                          qdd = ref->qdd.row(k).transpose();
    const Eigen::MatrixXd jac = ToolJacobian(hat, q, tool);
    ref->p.row(k) = ToolPoint(hat, q, tool).transpose();
    ref->pd.row(k) = (jac * qd).transpose();
    ref->pdd.row(k) = (jac * qdd + ToolBiasAcceleration(hat, q, qd, tool)).transpose();
  }
}

}  // namespace

ArmReference ArmSceneReference(const ArmScene& scene) {
  const ArmTaskSpec& task = scene.task;
  const ArmModel& hat = scene.hat;
  if (task.type == "writing") {
    WritingTaskOptions options = task.writing;
    options.sample_time = scene.plant.sample_time;
    try {
      return WritingTaskReference(hat, options);
    } catch (const InputError& e) {
      throw InputError(SourceLocation{scene.path}, "the writing task cannot be drawn by '" + hat.name + "': " + e.what());
    }
  }
  const int n = hat.dof();
  const double ts = scene.plant.sample_time;
  if (task.type == "random") {
    ArmReference ref;
    try {
      ref = task.motion == "multisine"
                ? SampledReference(RandomTrainingTrajectory(hat, task.training, scene.seed), ts, task.training.seconds)
                : RandomStopAndGoReference(hat, task.training, scene.seed);
    } catch (const InputError& e) {
      throw InputError(SourceLocation{scene.path}, "the random task cannot be drawn for '" + hat.name + "': " + e.what());
    }
    FillToolPath(hat, task.writing.tool, &ref);
    return ref;
  }
  const auto samples = static_cast<Eigen::Index>(std::floor(task.duration / ts + 1e-9)) + 1;
  ArmReference ref;
  ref.sample_time = ts;
  ref.t.resize(samples);
  ref.q.resize(samples, n), ref.qd.setZero(samples, n), ref.qdd.setZero(samples, n);
  const double w = 2 * kPi * task.frequency;
  for (Eigen::Index k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * ts;
    ref.t[k] = t;
    if (task.type == "hold") {
      ref.q.row(k) = task.q.transpose();
    } else if (task.type == "step") {
      ref.q.row(k) = (t < task.at - 1e-12 ? task.q : task.to).transpose();
    } else {  // sinusoid
      ref.q.row(k) = (task.q + task.amplitude * std::sin(w * t)).transpose();
      ref.qd.row(k) = (task.amplitude * w * std::cos(w * t)).transpose();
      ref.qdd.row(k) = (-task.amplitude * w * w * std::sin(w * t)).transpose();
    }
  }
  FillToolPath(hat, task.writing.tool, &ref);
  return ref;
}

std::string ArmSceneTrajectoryCsv(const ArmScene& scene, const TrackingTrial& trial) {
  return FormatSensedArmLog(SensedArmLog(scene.sensors, trial, scene.seed));
}

std::vector<Eigen::VectorXd> IlcPostures(const ArmScene& scene, const ArmReference& reference) {
  if (!scene.ilc.postures.empty()) return scene.ilc.postures;
  // Seed 001: 16 static postures, 4 x 4 over joints 2 and 3 across the range the task
  // moves them through, the waist at the task's start.
  if (scene.plant.dof() >= 3) {
    return GridPostures(scene.plant, reference.q.row(0).transpose(), 1, 2, 4, reference.q.colwise().minCoeff().transpose(),
                        reference.q.colwise().maxCoeff().transpose());
  }
  std::vector<Eigen::VectorXd> postures;
  const Eigen::Index last = reference.q.rows() - 1;
  for (Eigen::Index i = 0; i < 4; ++i) postures.push_back(reference.q.row(last * i / 3).transpose());
  return postures;
}

}  // namespace twinsim
