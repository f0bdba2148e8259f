// The Python module `twinsim._twinsim` (pybind11): twinsim's own library, not a second
// implementation. Models load and validate through the same readers as files, the
// simulations step through the same loop and delay line as `twinsim run`, and the
// command functions call what the commands call, returning arrays and dicts instead of
// writing files. python/twinsim/__init__.py is the public face (docs/api.md).
//
// Arrays: logs and command sequences are read from any array NumPy can view as float64
// (one copy into twinsim's row structs, which the checks and the replay need anyway);
// results are written straight into new NumPy arrays, never through a second buffer.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <complex>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "analysis/arm_replay.h"
#include "analysis/omni_compare.h"
#include "batch/batch_runner.h"
#include "batch/sweep.h"
#include "control/computed_torque.h"
#include "analysis/omni_replay.h"
#include "backends/arm_backend_factory.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "diagnosis/arm_diagnosis.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "identification/wls_identification.h"
#include "io/csv_table.h"
#include "io/yaml_extends.h"
#include "io/yaml_overrides.h"
#include "learning/arm_predictor.h"
#include "learning/omni_features.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "robots/omni/omni_model_yaml_writer.h"
#include "scene/ilc_scene.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "sim/arm_simulation.h"
#include "sim/omni_simulation.h"
#include "tuning/pid_tuning.h"
#include "python/observer_binding.h"

namespace py = pybind11;

namespace twinsim {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// ---- model parameters as dotted keys -----------------------------------------------

// Python value -> YAML node (numbers, bools, strings, lists and dicts of them).
YAML::Node ToYaml(const py::handle& value) {
  if (value.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(value)) return YAML::Node(value.cast<bool>());
  if (py::isinstance<py::int_>(value)) return YAML::Node(value.cast<long long>());
  if (py::isinstance<py::float_>(value)) return YAML::Node(value.cast<double>());
  if (py::isinstance<py::str>(value)) return YAML::Node(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) {
    YAML::Node map(YAML::NodeType::Map);
    for (const auto& [k, v] : value.cast<py::dict>()) map[py::str(k).cast<std::string>()] = ToYaml(v);
    return map;
  }
  if (py::isinstance<py::sequence>(value) || py::isinstance<py::array>(value)) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const auto& v : value) list.push_back(ToYaml(v));
    return list;
  }
  // NumPy scalars and anything else with __float__.
  if (py::hasattr(value, "__float__")) return YAML::Node(value.cast<double>());
  throw InputError("cannot set a model key to a value of type " + py::str(value.get_type()).cast<std::string>());
}

// YAML scalar -> the Python number, bool or string it spells.
py::object ScalarToPython(const YAML::Node& node) {
  const std::string text = node.Scalar();
  if (node.Tag() != "!") {  // unquoted: a number or bool where it spells one
    long long i = 0;
    double d = 0;
    if (YAML::convert<long long>::decode(node, i) && text.find_first_of(".eE") == std::string::npos) return py::int_(i);
    if (YAML::convert<double>::decode(node, d)) return py::float_(d);
    bool b = false;
    if (YAML::convert<bool>::decode(node, b)) return py::bool_(b);
  }
  return py::str(text);
}

py::object NodeToPython(const YAML::Node& node) {
  if (node.IsScalar()) return ScalarToPython(node);
  if (node.IsSequence()) {
    py::list list;
    for (const auto& v : node) list.append(NodeToPython(v));
    return list;
  }
  if (node.IsMap()) {
    py::dict dict;
    for (const auto& kv : node) dict[py::str(kv.first.Scalar())] = NodeToPython(kv.second);
    return dict;
  }
  return py::none();
}

// Every leaf of a document as "a.b.0.c" -> value; lists of scalars are one value.
void Flatten(const YAML::Node& node, const std::string& prefix, py::dict* out) {
  if (node.IsMap()) {
    for (const auto& kv : node) {
      Flatten(kv.second, prefix.empty() ? kv.first.Scalar() : prefix + "." + kv.first.Scalar(), out);
    }
    return;
  }
  if (node.IsSequence()) {
    bool scalars = true;
    for (const auto& v : node) scalars = scalars && v.IsScalar();
    if (!scalars) {
      for (std::size_t i = 0; i < node.size(); ++i) Flatten(node[i], prefix + "." + std::to_string(i), out);
      return;
    }
  }
  (*out)[py::str(prefix)] = NodeToPython(node);
}

// The node at a dotted key, or an invalid node.
YAML::Node Find(YAML::Node node, const std::string& key) {
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = key.find('.', start);
    const std::string step = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (node.IsMap()) {
      node = node[step];
    } else if (node.IsSequence()) {
      std::size_t index = 0;
      try {
        index = std::stoul(step);
      } catch (const std::exception&) {
        return YAML::Node(YAML::NodeType::Undefined);
      }
      if (index >= node.size()) return YAML::Node(YAML::NodeType::Undefined);
      node = node[index];
    } else {
      return YAML::Node(YAML::NodeType::Undefined);
    }
    if (!node.IsDefined()) return node;
    if (dot == std::string::npos) return node;
    start = dot + 1;
  }
}

// A model as Python sees it: the struct and its YAML text, kept in step. Keys are read
// from and written to the YAML, which is then read back by the model's own reader, so
// a bad value gets the file's checks and messages.
template <typename Model>
struct PyModel {
  Model model;
  std::string Yaml() const;
  static Model Parse(const std::string& yaml, const std::string& name);

  py::object Get(const std::string& key) const {
    const YAML::Node node = Find(YAML::Load(Yaml()), key);
    if (!node.IsDefined()) throw py::key_error(key);
    return NodeToPython(node);
  }
  void Set(const std::string& key, const py::handle& value) {
    const YAML::Node root = ApplyYamlOverrides(YAML::Load(Yaml()), {{key, ToYaml(value)}}, model.name);
    YAML::Emitter out;
    out << root;
    model = Parse(out.c_str(), model.name + " (set " + key + ")");
  }
  py::dict Dict() const {
    py::dict flat;
    Flatten(YAML::Load(Yaml()), "", &flat);
    return flat;
  }
};

template <>
std::string PyModel<OmniModel>::Yaml() const { return FormatOmniModelYaml(model); }
template <>
OmniModel PyModel<OmniModel>::Parse(const std::string& yaml, const std::string& name) {
  return LoadOmniModelFromString(yaml, name);
}
template <>
std::string PyModel<ArmModel>::Yaml() const { return FormatArmModelYaml(model); }
template <>
ArmModel PyModel<ArmModel>::Parse(const std::string& yaml, const std::string& name) {
  return LoadArmModelFromYamlString(yaml, name);
}

using PyOmniModel = PyModel<OmniModel>;
using PyArmModel = PyModel<ArmModel>;

template <typename Model>
void BindModelView(py::class_<PyModel<Model>>& cls) {
  cls.def_property_readonly("name", [](const PyModel<Model>& m) { return m.model.name; })
      .def("__getitem__", &PyModel<Model>::Get, py::arg("key"))
      .def("__setitem__", &PyModel<Model>::Set, py::arg("key"), py::arg("value"))
      .def("__contains__", [](const PyModel<Model>& m, const std::string& key) {
        return Find(YAML::Load(m.Yaml()), key).IsDefined();
      })
      .def("keys", [](const PyModel<Model>& m) { return m.Dict().attr("keys")(); })
      .def("to_dict", &PyModel<Model>::Dict, "Every parameter as a flat dict of dotted keys")
      .def("to_yaml", &PyModel<Model>::Yaml, "The model file's text (loads in every command)")
      .def("copy", [](const PyModel<Model>& m) { return PyModel<Model>(m); })
      .def("__copy__", [](const PyModel<Model>& m) { return PyModel<Model>(m); })
      .def("__deepcopy__", [](const PyModel<Model>& m, py::dict) { return PyModel<Model>(m); });
}

// ---- logs from arrays ------------------------------------------------------------------

std::vector<std::vector<double>> Rows(const Array& a, int cols, const std::string& what) {
  if (a.ndim() != 2 || a.shape(1) != cols) {
    std::ostringstream msg;
    msg << what << ": expected an array of shape (N, " << cols << "), got shape (";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) msg << (i ? ", " : "") << a.shape(i);
    msg << ")";
    throw InputError(msg.str());
  }
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(a.shape(0)), std::vector<double>(cols));
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int j = 0; j < cols; ++j) rows[static_cast<std::size_t>(i)][j] = r(i, j);
  return rows;
}

// An omni log: a file path, or an (N, 7) array t,x,y,theta,vx_cmd,vy_cmd,omega_cmd.
OmniLog ToOmniLog(const py::handle& log, const std::string& name) {
  if (py::isinstance<py::str>(log)) return ReadOmniLog(log.cast<std::string>());
  return OmniLogFromTable(TableFromRows(name, {"t", "x", "y", "theta", "vx_cmd", "vy_cmd", "omega_cmd"},
                                        Rows(log.cast<Array>(), 7, name)));
}

// An arm log: a file path, or a dict of arrays t (N), q, tau and optionally qd, qdd,
// qref (N x n each).
ArmLog ToArmLog(const py::handle& log, const std::string& name) {
  if (py::isinstance<py::str>(log)) return ReadArmLog(log.cast<std::string>());
  if (!py::isinstance<py::dict>(log)) throw InputError(name + ": an arm log is a file path or a dict of arrays (t, q, tau)");
  const py::dict d = log.cast<py::dict>();
  for (const char* key : {"t", "q", "tau"}) {
    if (!d.contains(key)) throw InputError(name + ": missing '" + std::string(key) + "' (an arm log needs t, q and tau)");
  }
  const Array t = d["t"].cast<Array>();
  if (t.ndim() != 1) throw InputError(name + ": 't' must be one-dimensional");
  const py::ssize_t n = t.shape(0);
  std::vector<std::string> header{"t"};
  std::vector<Array> blocks;
  int dof = -1;
  for (const char* key : {"q", "qd", "qdd", "tau", "qref"}) {
    if (!d.contains(key)) continue;
    Array a = d[key].cast<Array>();
    if (a.ndim() == 1) a = a.reshape({a.shape(0), py::ssize_t{1}});
    if (a.ndim() != 2 || a.shape(0) != n) {
      throw InputError(name + ": '" + key + "' must have one row per time (" + std::to_string(n) + " rows)");
    }
    if (dof < 0) dof = static_cast<int>(a.shape(1));
    if (a.shape(1) != dof) throw InputError(name + ": '" + key + "' has another number of joints than 'q'");
    for (int j = 0; j < dof; ++j) header.push_back(key + std::to_string(j + 1));
    blocks.push_back(std::move(a));
  }
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(n));
  auto tt = t.unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    auto& row = rows[static_cast<std::size_t>(i)];
    row.reserve(header.size());
    row.push_back(tt(i));
    for (const Array& b : blocks) {
      auto bb = b.unchecked<2>();
      for (py::ssize_t j = 0; j < b.shape(1); ++j) row.push_back(bb(i, j));
    }
  }
  return ArmLogFromTable(TableFromRows(name, std::move(header), std::move(rows)));
}

std::string LogName(int i) { return "log[" + std::to_string(i) + "]"; }

// One log (`single`) or a list of them, each read by `one(log, name)`.
template <typename Log, typename ReadOne>
std::vector<Log> ToLogs(const py::handle& logs, bool single, ReadOne one) {
  std::vector<Log> out;
  if (single) {
    out.push_back(one(logs, LogName(0)));
    return out;
  }
  int i = 0;
  for (const auto& log : logs) out.push_back(one(log, LogName(i++)));
  return out;
}

std::vector<OmniLog> ToOmniLogs(const py::handle& logs) {
  return ToLogs<OmniLog>(logs, py::isinstance<py::str>(logs) || py::isinstance<py::array>(logs), ToOmniLog);
}

std::vector<ArmLog> ToArmLogs(const py::handle& logs) {
  return ToLogs<ArmLog>(logs, py::isinstance<py::str>(logs) || py::isinstance<py::dict>(logs), ToArmLog);
}

// A new (rows, cols) float64 array.
Array NewArray(py::ssize_t rows, py::ssize_t cols) { return Array({rows, cols}); }

// ---- predictors --------------------------------------------------------------------

std::shared_ptr<const OmniPredictor> OmniPredictorArg(const py::handle& p) {
  if (p.is_none()) return nullptr;
  if (py::isinstance<py::str>(p)) return std::make_shared<OmniPredictor>(OmniPredictor::Load(p.cast<std::string>()));
  return p.cast<std::shared_ptr<OmniPredictor>>();
}

std::shared_ptr<const ArmPredictor> ArmPredictorArg(const py::handle& p) {
  if (p.is_none()) return nullptr;
  if (py::isinstance<py::str>(p)) return std::make_shared<ArmPredictor>(ArmPredictor::Load(p.cast<std::string>()));
  return p.cast<std::shared_ptr<ArmPredictor>>();
}

// ---- omni simulation ---------------------------------------------------------------

// The command a robot's "behaviour" sends: whatever Python set last.
class ExternalCommand : public CommandSource {
 public:
  explicit ExternalCommand(std::shared_ptr<Twist2> command) : command_(std::move(command)) {}
  Twist2 Command(const BehaviourInput&) override { return *command_; }
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<ExternalCommand>(command_); }

 private:
  std::shared_ptr<Twist2> command_;
};

class PyOmniSim {
 public:
  PyOmniSim(Scene scene, std::string backend, const py::handle& predictor, std::optional<std::uint64_t> seed,
            bool external)
      : scene_(std::move(scene)),
        backend_(std::move(backend)),
        predictor_(OmniPredictorArg(predictor)),
        external_(external) {
    if (seed) scene_.seed = *seed;
    Reset(std::nullopt);
  }

  // The scene's simulation as `twinsim run` makes it (MakeSimulation: the robots' own
  // backends, the ball, the learned backend's messages), with external commands when
  // Python drives the robots.
  void Reset(std::optional<std::uint64_t> seed) {
    if (seed) scene_.seed = *seed;
    commands_.clear();
    CommandSourceFactory external;
    if (external_) {
      external = [this](std::size_t) -> std::unique_ptr<CommandSource> {
        commands_.push_back(std::make_shared<Twist2>());
        return std::make_unique<ExternalCommand>(commands_.back());
      };
    }
    OmniBackendOptions options;
    options.predictor = predictor_;
    sim_ = std::make_unique<Simulation>(MakeSimulation(scene_, backend_, options, external));
    last_.assign(scene_.robots.size(), FrameRecord{});
  }

  int robots() const { return static_cast<int>(scene_.robots.size()); }

  // Sets the commands (robot frame: vx, vy m/s, omega rad/s): (3,) for one robot or
  // (robots, 3).
  void SetCommands(const Array& c) {
    if (!external_) throw InputError("this simulation's robots follow the scene's behaviours (external=False)");
    const int n = robots();
    const bool one = c.ndim() == 1 && c.shape(0) == 3 && n == 1;
    if (!one && !(c.ndim() == 2 && c.shape(0) == n && c.shape(1) == 3)) {
      throw InputError("commands: expected shape (" + std::to_string(n) + ", 3)" + (n == 1 ? " or (3,)" : ""));
    }
    const double* p = c.data();
    for (int i = 0; i < n; ++i) {
      const Twist2 t{p[3 * i], p[3 * i + 1], p[3 * i + 2]};
      if (!IsFinite(t)) throw InputError("commands: robot " + std::to_string(i) + " has a non-finite command");
      *commands_[static_cast<std::size_t>(i)] = t;
    }
  }

  void Step(const py::handle& commands) {
    if (!commands.is_none()) SetCommands(commands.cast<Array>());
    last_ = sim_->Step();
  }

  // Runs one frame per row of `commands` (frames, robots, 3) or (frames, 3), or `frames`
  // frames of the scene's behaviours; returns the run as arrays.
  py::dict Run(const py::handle& commands, int frames) {
    const int n = robots();
    Array c;
    const bool given = !commands.is_none();
    if (given) {
      c = commands.cast<Array>();
      if (c.ndim() == 2 && n == 1) c = c.reshape({c.shape(0), py::ssize_t{1}, py::ssize_t{3}});
      if (c.ndim() != 3 || c.shape(1) != n || c.shape(2) != 3) {
        throw InputError("commands: expected shape (frames, " + std::to_string(n) + ", 3)" +
                         (n == 1 ? " or (frames, 3)" : ""));
      }
      frames = static_cast<int>(c.shape(0));
    }
    if (frames < 0) throw InputError("frames must not be negative");
    Array t({py::ssize_t{frames}});
    std::vector<py::ssize_t> shape{frames, n, 3};
    Array truth(shape), velocity(shape), seen(shape), sent(shape);
    py::array_t<bool> observed({py::ssize_t{frames}, py::ssize_t{n}});
    double* pt = t.mutable_data();
    double *ptr = truth.mutable_data(), *pv = velocity.mutable_data(), *ps = seen.mutable_data(),
           *pc = sent.mutable_data();
    bool* po = observed.mutable_data();
    for (int k = 0; k < frames; ++k) {
      if (given) {
        const double* row = c.data() + static_cast<std::ptrdiff_t>(k) * n * 3;
        for (int i = 0; i < n; ++i) {
          const Twist2 tw{row[3 * i], row[3 * i + 1], row[3 * i + 2]};
          if (!IsFinite(tw)) throw InputError("commands: frame " + std::to_string(k) + " has a non-finite command");
          *commands_[static_cast<std::size_t>(i)] = tw;
        }
      }
      last_ = sim_->Step();
      pt[k] = last_[0].t;
      for (int i = 0; i < n; ++i) {
        const FrameRecord& r = last_[static_cast<std::size_t>(i)];
        const std::ptrdiff_t at = (static_cast<std::ptrdiff_t>(k) * n + i) * 3;
        ptr[at] = r.truth.x, ptr[at + 1] = r.truth.y, ptr[at + 2] = r.truth.theta;
        pv[at] = r.truth_velocity.vx, pv[at + 1] = r.truth_velocity.vy, pv[at + 2] = r.truth_velocity.omega;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        ps[at] = r.observed ? r.seen.x : nan, ps[at + 1] = r.observed ? r.seen.y : nan;
        ps[at + 2] = r.observed ? r.seen.theta : nan;
        pc[at] = r.command.vx, pc[at + 1] = r.command.vy, pc[at + 2] = r.command.omega;
        po[static_cast<std::ptrdiff_t>(k) * n + i] = r.observed;
      }
    }
    py::dict out;
    out["t"] = t;
    out["truth"] = truth;
    out["truth_velocity"] = velocity;
    // Python's names read as English and match the `observed` property (poses): "observed"
    // holds the poses the camera delivered (NaN where lost), "seen" whether it delivered
    // one. FrameRecord names them the other way round (`seen` the pose, `observed` the
    // flag); docs/api.md gives the mapping.
    out["observed"] = seen;
    out["seen"] = observed;
    out["command"] = sent;
    return out;
  }

  // Per robot, 3 numbers of each robot's last record.
  template <typename Get>
  Array PerRobot(Get get) const {
    Array a = NewArray(robots(), 3);
    double* p = a.mutable_data();
    for (int i = 0; i < robots(); ++i) {
      const auto v = get(last_[static_cast<std::size_t>(i)]);
      p[3 * i] = v[0], p[3 * i + 1] = v[1], p[3 * i + 2] = v[2];
    }
    return a;
  }

  Array Truth() const {
    return PerRobot([](const FrameRecord& r) { return std::array<double, 3>{r.truth.x, r.truth.y, r.truth.theta}; });
  }
  Array TruthVelocity() const {
    return PerRobot([](const FrameRecord& r) {
      return std::array<double, 3>{r.truth_velocity.vx, r.truth_velocity.vy, r.truth_velocity.omega};
    });
  }
  Array Observed() const {
    return PerRobot([](const FrameRecord& r) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      return r.observed ? std::array<double, 3>{r.seen.x, r.seen.y, r.seen.theta} : std::array<double, 3>{nan, nan, nan};
    });
  }

  double time() const { return last_.empty() ? 0 : last_[0].t; }
  int frame() const { return sim_->frame(); }
  // The ball's true centre (x, y, z) now, or None on a field without one.
  py::object Ball() const {
    if (!sim_->has_ball()) return py::none();
    const Eigen::Vector3d& p = sim_->ball_record().truth.position;
    Array a({py::ssize_t{3}});
    std::copy(p.data(), p.data() + 3, a.mutable_data());
    return a;
  }
  const Scene& scene() const { return scene_; }
  // The backend's name: `backend`, or "mixed: ..." where robots name their own.
  std::string backend() const { return sim_->backend().name(); }

 private:
  Scene scene_;
  std::string backend_;
  std::shared_ptr<const OmniPredictor> predictor_;
  bool external_;
  std::unique_ptr<Simulation> sim_;
  std::vector<std::shared_ptr<Twist2>> commands_;
  std::vector<FrameRecord> last_;
};

// A one-robot scene around a model: the robot at the origin, default field, camera at
// `frame_rate`.
Scene SceneOfModel(const OmniModel& model, double frame_rate) {
  Scene scene;
  scene.path = "(python)";
  scene.name = model.name;
  scene.frame_rate = frame_rate;
  SceneRobot robot;
  robot.name = model.name;
  robot.model = model;
  scene.robots.push_back(robot);
  return scene;
}

// ---- arm simulation ----------------------------------------------------------------

class PyArmSim {
 public:
  PyArmSim(const ArmModel& model, const std::string& backend, const py::handle& predictor)
      : model_(model), backend_(backend) {
    ArmBackendOptions options;
    options.predictor = ArmPredictorArg(predictor);
    sim_ = std::make_unique<ArmSimulation>(model_, MakeArmBackend(backend_, model_, options));
    command_ = Eigen::VectorXd::Zero(model_.dof());
    q_ = Eigen::VectorXd::Zero(model_.dof());
    qd_ = q_;
  }

  void Reset(const std::optional<Eigen::VectorXd>& q, const std::optional<Eigen::VectorXd>& qd) {
    const int n = model_.dof();
    const Eigen::VectorXd q0 = q ? *q : Eigen::VectorXd::Zero(n);
    const Eigen::VectorXd qd0 = qd ? *qd : Eigen::VectorXd::Zero(n);
    if (q0.size() != n || qd0.size() != n || !q0.allFinite() || !qd0.allFinite()) {
      throw InputError("reset: q and qd need " + std::to_string(n) + " finite numbers each");
    }
    sim_->Reset(q0, qd0);
    q_ = q0, qd_ = qd0, t_ = 0;
  }

  // Sends `tau` (dof torques or forces) for one sample; the model's delay applies.
  void Step(const Eigen::VectorXd& tau) {
    if (tau.size() != model_.dof()) throw InputError("step: expected " + std::to_string(model_.dof()) + " torques");
    if (!tau.allFinite()) throw InputError("step: the torques must be finite");
    command_ = tau;
    sim_->Step([this](double, const Eigen::VectorXd&, const Eigen::VectorXd&) { return command_; });
    q_ = sim_->backend().q(), qd_ = sim_->backend().qd(), t_ = sim_->time();
  }

  // A tracking controller over `hat` (the controller's model of the arm), run at each
  // sample on the sampled state as in `twinsim run`'s arm scenes: "computed_torque" or
  // "pd_feedforward" at `bandwidth` Hz with `damping`, friction compensated or not.
  void SetController(const std::string& kind, const ArmModel& hat, double bandwidth, double damping, bool friction) {
    if (kind != "computed_torque" && kind != "pd_feedforward") {
      throw InputError("controller '" + kind + "': known are computed_torque and pd_feedforward");
    }
    if (hat.dof() != model_.dof()) throw InputError("controller: the model '" + hat.name + "' has another number of joints");
    if (!(bandwidth > 0 && bandwidth < 1e4) || !(damping > 0 && damping < 100)) {
      throw InputError("controller: bandwidth must be 0 to 1e4 Hz and damping 0 to 100");
    }
    hat_ = hat;
    controller_ = kind;
    friction_ = friction;
    gains_ = kind == "computed_torque" ? ComputedTorqueGains(hat.dof(), bandwidth, damping)
                                       : PdFeedforwardGains(hat, q_, bandwidth, damping);
  }

  // One sample tracking the reference (q_r, qd_r, qdd_r) with the controller; returns
  // the torque it sent.
  Eigen::VectorXd StepReference(const Eigen::VectorXd& q_r, const Eigen::VectorXd& qd_r, const Eigen::VectorXd& qdd_r) {
    if (controller_.empty()) throw InputError("step_reference: set_controller first");
    const int n = model_.dof();
    if (q_r.size() != n || qd_r.size() != n || qdd_r.size() != n || !q_r.allFinite() || !qd_r.allFinite() ||
        !qdd_r.allFinite()) {
      throw InputError("step_reference: q_r, qd_r and qdd_r need " + std::to_string(n) + " finite numbers each");
    }
    Eigen::VectorXd sent;
    sim_->Step([&](double, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
      sent = controller_ == "computed_torque"
                 ? ComputedTorque(hat_, gains_, friction_, qd_r, q_r, qd_r, qdd_r, q, qd, nullptr)
                 : PdFeedforwardTorque(hat_, gains_, friction_, q_r, qd_r, qdd_r, q, qd, nullptr);
      return sent;
    });
    q_ = sim_->backend().q(), qd_ = sim_->backend().qd(), t_ = sim_->time();
    return sent;
  }

  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }
  double time() const { return t_; }
  int dof() const { return model_.dof(); }
  double sample_time() const { return model_.sample_time; }

 private:
  ArmModel model_;
  std::string backend_;
  std::unique_ptr<ArmSimulation> sim_;
  Eigen::VectorXd command_, q_, qd_;
  double t_ = 0;
  ArmModel hat_;
  std::string controller_;  // empty: torques from Python only
  bool friction_ = true;
  TrackingGains gains_;
};

// ---- the command functions ---------------------------------------------------------

Array ReplayOmni(const OmniModel& model, const py::handle& log, const std::string& backend, int horizon,
                 const py::handle& predictor, const std::string& state) {
  const OmniLog l = ToOmniLog(log, "log");
  OmniReplayOptions options;
  options.backend = backend;
  options.horizon = horizon;
  options.state = state;
  options.backend_options.predictor = OmniPredictorArg(predictor);
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  const OmniReplayResult r = ReplayOmniLog(model, l, options);
  Array out = NewArray(static_cast<py::ssize_t>(r.t.size()), 4);
  double* p = out.mutable_data();
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    p[4 * i] = r.t[i], p[4 * i + 1] = r.pose[i].x, p[4 * i + 2] = r.pose[i].y, p[4 * i + 3] = r.pose[i].theta;
  }
  return out;
}

Eigen::MatrixXd ReplayArm(const ArmModel& model, const py::handle& log) {
  const ArmLog l = ToArmLog(log, "log");
  CheckArmLogMatchesModel(l, model);
  return PredictArmTorques(model, l);
}

// (X, Y) training data of the omni predictor: X (N, inputs), Y (N, 3) pose changes.
py::tuple OmniTrainingData(const OmniModel& model, const py::handle& logs, int horizon) {
  if (horizon < 1 || horizon > 100) throw InputError("horizon must be 1 to 100 frames");
  const FeatureLayout layout = PredictorLayout(model, horizon);
  OmniDataset data;
  for (const OmniLog& log : ToOmniLogs(logs)) AppendSamples(log, layout, &data);
  return py::make_tuple(data.x, data.y);
}

std::shared_ptr<OmniPredictor> TrainOmni(const OmniModel& model, const py::handle& logs, const std::string& kind,
                                         int horizon, bool residual, const std::string& nominal_engine,
                                         std::uint64_t seed, int epochs, std::vector<int> hidden) {
  OmniTrainOptions options;
  options.kind = kind;
  options.horizon = horizon;
  options.residual = residual;
  options.nominal_engine = nominal_engine;
  options.mlp.seed = seed;
  options.mlp.max_epochs = epochs;
  options.mlp.hidden = std::move(hidden);
  return std::make_shared<OmniPredictor>(TrainOmniPredictor(model, ToOmniLogs(logs), options));
}

std::shared_ptr<ArmPredictor> TrainArm(const ArmModel& model, const py::handle& logs, const std::string& kind,
                                       bool residual, std::uint64_t seed, int epochs, std::vector<int> hidden) {
  ArmTrainOptions options;
  options.kind = kind;
  options.residual = residual;
  options.mlp.seed = seed;
  options.mlp.max_epochs = epochs;
  options.mlp.hidden = std::move(hidden);
  return std::make_shared<ArmPredictor>(TrainArmPredictor(model, ToArmLogs(logs), options));
}

// (report as JSON text, repaired model YAML)
py::tuple Diagnose(const py::handle& model, const py::handle& logs, double held_out, int max_effects,
                   const std::string& backend, int threads, bool refit_model) {
  DiagnosisOptions options;
  options.held_out = held_out;
  options.max_effects = max_effects;
  options.backend = backend;
  options.threads = threads;
  options.refit_model = refit_model;
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (py::isinstance<PyArmModel>(model)) {
    ArmModel repaired;
    const DiagnosisReport report =
        DiagnoseArm(model.cast<const PyArmModel&>().model, ToArmLogs(logs), options, &repaired, {});
    return py::make_tuple(FormatDiagnosisJson(report), PyArmModel{repaired});
  }
  OmniModel repaired;
  const DiagnosisReport report =
      DiagnoseOmni(model.cast<const PyOmniModel&>().model, ToOmniLogs(logs), options, &repaired, {});
  return py::make_tuple(FormatDiagnosisJson(report), PyOmniModel{repaired});
}

// `twinsim compare`: the error rows as dicts and each free run as an (N, 4) array.
py::dict Compare(const OmniModel& model, const py::handle& log, std::vector<std::string> backends,
                 const py::handle& predictor) {
  const OmniLog l = ToOmniLog(log, "log");
  const OmniCompareOptions options = MakeCompareOptions(model, l, std::move(backends), OmniPredictorArg(predictor));
  const OmniCompareResult result = CompareOmniLog(model, l, options);
  py::list rows;
  for (const CompareErrorRow& r : result.rows) {
    py::dict row;
    row["source"] = r.source;
    row["backend"] = r.backend;
    row["horizon"] = r.horizon;
    row["horizon_frames"] = r.horizon_frames;
    row["predicted"] = r.predicted;
    row["position_rmse"] = r.position_rmse;
    row["position_max"] = r.position_max;
    row["heading_rmse"] = r.heading_rmse;
    rows.append(row);
  }
  py::dict free_runs;
  for (const ComparePath& path : result.free_runs) {
    Array a = NewArray(static_cast<py::ssize_t>(path.t.size()), 4);
    double* p = a.mutable_data();
    for (std::size_t i = 0; i < path.t.size(); ++i) {
      p[4 * i] = path.t[i], p[4 * i + 1] = path.pose[i].x, p[4 * i + 2] = path.pose[i].y;
      p[4 * i + 3] = path.pose[i].theta;
    }
    free_runs[py::str(path.source)] = a;
  }
  py::dict out;
  out["rows"] = rows;
  out["free_runs"] = free_runs;
  out["frame_rate"] = result.frame_rate;
  return out;
}

py::dict Score(const TestRunScore& s) {
  py::dict d;
  d["quality"] = s.quality;
  d["distance"] = s.distance;
  d["deviation"] = s.deviation;
  d["rotation"] = s.rotation;
  d["stop_distance"] = s.stop_distance;
  d["avg_speed"] = s.avg_speed;
  d["end_deviation_pct"] = s.end_deviation_pct;
  return d;
}

// `twinsim tune-pid`: learning.csv's rows as dicts, the parameters per iteration as an
// (iterations, 18) array, and the best set by name.
py::dict TunePidFunction(Scene scene, int iterations, const std::string& backend, int threads,
                         std::optional<std::uint64_t> seed, const std::string& start) {
  if (seed) scene.seed = *seed;
  PidTuningOptions tuning = ReadPidTuningOptions(scene);
  if (iterations > 0) tuning.iterations = iterations;
  if (!start.empty()) tuning.start = start;
  tuning.threads = threads;
  std::string why;
  if (!tuning.IsValid(&why)) throw InputError(SourceLocation{scene.path}, "tune_pid: " + why);
  const TestRunEvaluator evaluator(scene, backend.empty() ? scene.backend : backend, tuning.weights);
  const PidTuningResult r = TunePid(evaluator, tuning, {});
  py::list learning;
  Array parameters = NewArray(static_cast<py::ssize_t>(r.iterations.size()), kPidParameters);
  for (std::size_t i = 0; i < r.iterations.size(); ++i) {
    py::dict row = Score(r.iterations[i].score);
    row["iteration"] = r.iterations[i].iteration;
    learning.append(row);
    for (int k = 0; k < kPidParameters; ++k) parameters.mutable_data()[i * kPidParameters + k] = r.iterations[i].parameters[k];
  }
  py::dict best;
  const std::vector<std::string> names = PidParameterNames();
  for (int k = 0; k < kPidParameters; ++k) best[py::str(names[static_cast<std::size_t>(k)])] = r.best_parameters[k];
  py::dict out;
  out["learning"] = learning;
  out["parameters"] = parameters;
  out["parameter_names"] = names;
  out["best"] = best;
  out["best_score"] = Score(r.best_score);
  out["test_runs"] = r.test_runs;
  return out;
}

// `twinsim batch`: runs the sweep into `out` (a sweep's product is its job folders) and
// returns summary.csv as a dict of columns (numbers as arrays, text as lists).
py::dict BatchFunction(const std::string& sweep_path, const std::string& out, int jobs, bool resume) {
  BatchOptions options;
  options.out = out;
  options.jobs = jobs;
  options.resume = resume;
  options.progress = false;
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  const BatchSummary summary = RunBatch(LoadSweep(sweep_path), options);
  const CsvTable table = ReadCsvTable(out + "/summary.csv");
  py::dict columns;
  for (std::size_t c = 0; c < table.header.size(); ++c) {
    if (table.problem[c].line == 0) {
      Array a({static_cast<py::ssize_t>(table.rows.size())});
      for (std::size_t r = 0; r < table.rows.size(); ++r) a.mutable_data()[r] = table.rows[r][c];
      columns[py::str(table.header[c])] = a;
    } else {
      columns[py::str(table.header[c])] = py::none();  // text: read below from the file itself
    }
  }
  py::dict result;
  result["columns"] = columns;
  result["jobs"] = summary.jobs;
  result["ran"] = summary.ran;
  result["resumed"] = summary.resumed;
  result["failed"] = summary.failed;
  result["summary_csv"] = out + "/summary.csv";
  return result;
}

// `twinsim ilc`: the trials' errors, the measured process sensitivities and the filters.
py::dict IlcFunction(const std::string& scene_path, int trials, const std::string& backend) {
  const IlcSceneRun run = RunIlcScene(LoadArmScene(scene_path), backend, trials);
  const IlcResult& r = run.result;
  const int n = static_cast<int>(run.filters.size());
  Array rms = NewArray(static_cast<py::ssize_t>(r.error_rms.size()), n);
  Array max = NewArray(static_cast<py::ssize_t>(r.error_max.size()), n);
  for (std::size_t k = 0; k < r.error_rms.size(); ++k) {
    for (int j = 0; j < n; ++j) {
      rms.mutable_data()[k * n + j] = r.error_rms[k][j];
      max.mutable_data()[k * n + j] = r.error_max[k][j];
    }
  }
  const ClosedLoopFrf& frf = run.frf;
  const auto lines = static_cast<py::ssize_t>(frf.frequency.size());
  const auto postures = static_cast<py::ssize_t>(frf.postures.size());
  py::array_t<std::complex<double>> ps({static_cast<py::ssize_t>(n), postures, lines});
  for (int j = 0; j < n; ++j)
    for (py::ssize_t p = 0; p < postures; ++p)
      for (py::ssize_t i = 0; i < lines; ++i)
        ps.mutable_data()[(j * postures + p) * lines + i] = frf.response[static_cast<std::size_t>(j)][static_cast<std::size_t>(p)](i);
  py::list filters;
  for (const LearningFilter& f : run.filters) filters.append(f.Summary());
  py::dict out;
  out["rms"] = rms;
  out["max"] = max;
  out["frequency"] = Eigen::VectorXd(frf.frequency);
  out["process_sensitivity"] = ps;
  out["postures"] = frf.postures;
  out["filters"] = filters;
  out["reduction"] = r.Reduction();
  out["diverged"] = r.Diverged();
  out["backend"] = run.backend;
  return out;
}

// `twinsim run` of an arm scene without files: the task under the scene's controller on
// `backend` (empty: the scene's), as arrays.
py::dict RunArmSceneFunction(const std::string& path, const std::string& backend, const py::handle& predictor,
                             std::optional<std::uint64_t> seed) {
  ArmScene scene = LoadArmScene(path);
  if (seed) scene.seed = *seed;
  const std::string p = predictor.is_none() ? "" : predictor.cast<std::string>();
  const TrackingTrial trial = RunArmScene(scene, backend.empty() ? scene.backend : backend, p);
  py::dict out;
  out["t"] = trial.t;
  out["q"] = trial.q;
  out["qd"] = trial.qd;
  out["q_ref"] = trial.q_ref;
  out["command"] = trial.command;
  out["applied"] = trial.applied;
  out["error_rms"] = trial.error_rms;
  out["error_max"] = trial.error_max;
  out["backend"] = trial.backend;
  return out;
}

}  // namespace
}  // namespace twinsim

PYBIND11_MODULE(_twinsim, m) {
  using namespace twinsim;
  m.doc() = "twinsim's C++ library (use the twinsim package, not this module)";

  // Errors: the same messages as on the command line ("path:line: what is wrong").
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<CheckFailed> check_failed(m, "CheckFailed", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const CheckFailed& e) {
      check_failed(e.what());
    } catch (const YAML::Exception& e) {
      input_error(e.what());
    }
  });

  py::class_<PyOmniModel> omni_model(m, "OmniModel", "An omni robot model (docs/models.md); keys as in its YAML");
  BindModelView(omni_model);
  omni_model.def_property_readonly("delay_frames", [](const PyOmniModel& m) {
    return m.model.command_delay_frames + m.model.vision_delay_frames;
  });
  py::class_<PyArmModel> arm_model(m, "ArmModel", "An arm model (URDF or YAML); keys as in its YAML form");
  BindModelView(arm_model);
  arm_model.def_property_readonly("dof", [](const PyArmModel& m) { return m.model.dof(); })
      .def_property_readonly("sample_time", [](const PyArmModel& m) { return m.model.sample_time; })
      .def_property_readonly("joint_names", [](const PyArmModel& m) {
        std::vector<std::string> names;
        for (const auto& j : m.model.joints) names.push_back(j.name);
        return names;
      });

  BindOmniObserver(m, [](const py::handle& model) { return model.cast<const PyOmniModel&>().model; });
  m.def("load_omni_model", [](const std::string& path) { return PyOmniModel{LoadOmniModel(path)}; }, py::arg("path"));
  m.def("load_arm_model", [](const std::string& path) { return PyArmModel{LoadArmModel(path)}; }, py::arg("path"));
  m.def("omni_model_from_yaml", [](const std::string& text, const std::string& name) {
    return PyOmniModel{LoadOmniModelFromString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");
  m.def("arm_model_from_yaml", [](const std::string& text, const std::string& name) {
    return PyArmModel{LoadArmModelFromYamlString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");
  m.def("arm_model_from_urdf", [](const std::string& text, const std::string& name) {
    return PyArmModel{LoadArmModelFromUrdfString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");

  py::class_<Scene>(m, "Scene", "An omni scene (docs/scenes.md)")
      .def_readonly("name", &Scene::name)
      .def_readonly("path", &Scene::path)
      .def_readonly("backend", &Scene::backend)
      .def_readonly("duration", &Scene::duration)
      .def_readonly("frame_rate", &Scene::frame_rate)
      .def_readonly("seed", &Scene::seed)
      .def_property_readonly("frames", &Scene::num_frames)
      .def_property_readonly("robot_names", [](const Scene& s) {
        std::vector<std::string> names;
        for (const auto& r : s.robots) names.push_back(r.name);
        return names;
      });
  m.def("load_scene", [](const std::string& path) { return LoadScene(path); }, py::arg("path"));

  py::class_<OmniPredictor, std::shared_ptr<OmniPredictor>>(m, "OmniPredictor", "A learned omni model (twinsim train)")
      .def_static("load", [](const std::string& path) { return std::make_shared<OmniPredictor>(OmniPredictor::Load(path)); })
      .def_static("linear", [](const PyOmniModel& model, const Eigen::MatrixXd& weights, const Eigen::Vector3d& bias,
                               int horizon, double frame_rate) {
        return std::make_shared<OmniPredictor>(MakeLinearOmniPredictor(model.model, frame_rate, horizon, weights, bias));
      }, py::arg("model"), py::arg("weights"), py::arg("bias"), py::arg("horizon") = 1, py::arg("frame_rate") = 30.0)
      .def("save", &OmniPredictor::Save, py::arg("path"))
      .def_property_readonly("kind", [](const OmniPredictor& p) { return p.info().kind; })
      .def_property_readonly("residual", &OmniPredictor::residual)
      .def_property_readonly("nominal_engine", [](const OmniPredictor& p) { return p.info().nominal_engine; })
      .def_property_readonly("horizon", [](const OmniPredictor& p) { return p.info().layout.horizon; })
      .def_property_readonly("num_inputs", [](const OmniPredictor& p) { return p.info().layout.num_inputs(); })
      .def_property_readonly("model_name", [](const OmniPredictor& p) { return p.info().model_name; })
      .def_property_readonly("frame_rate", [](const OmniPredictor& p) { return p.info().frame_rate; })
      .def("predict_delta", [](const OmniPredictor& p, const twinsim::Array& x) {
        const int n = p.info().layout.num_inputs();
        if (x.ndim() != 2 || x.shape(1) != n) throw InputError("predict_delta: expected shape (N, " + std::to_string(n) + ")");
        twinsim::Array out = twinsim::NewArray(x.shape(0), 3);
        for (py::ssize_t i = 0; i < x.shape(0); ++i) {
          const Eigen::Vector3d d = p.PredictDelta(x.data() + i * n);
          out.mutable_data()[3 * i] = d[0], out.mutable_data()[3 * i + 1] = d[1], out.mutable_data()[3 * i + 2] = d[2];
        }
        return out;
      }, py::arg("inputs"), "Pose changes (robot frame) for rows of inputs as training_data lays them out");
  py::class_<ArmPredictor, std::shared_ptr<ArmPredictor>>(m, "ArmPredictor", "A learned arm model (twinsim train)")
      .def_static("load", [](const std::string& path) { return std::make_shared<ArmPredictor>(ArmPredictor::Load(path)); })
      .def("save", &ArmPredictor::Save, py::arg("path"));

  py::class_<PyOmniSim>(m, "OmniSim", "An omni scene stepped from Python through the delay loop of `twinsim run`")
      .def(py::init([](const py::handle& what, const std::string& backend, const py::handle& predictor,
                       std::optional<std::uint64_t> seed, bool external, double frame_rate) {
             Scene scene = py::isinstance<PyOmniModel>(what) ? SceneOfModel(what.cast<const PyOmniModel&>().model, frame_rate)
                                                             : what.cast<Scene>();
             return std::make_unique<PyOmniSim>(std::move(scene), backend, predictor, seed, external);
           }),
           py::arg("scene"), py::arg("backend") = "analytic", py::arg("predictor") = py::none(),
           py::arg("seed") = py::none(), py::arg("external") = true, py::arg("frame_rate") = 30.0)
      .def("reset", &PyOmniSim::Reset, py::arg("seed") = py::none())
      .def("step", &PyOmniSim::Step, py::arg("commands") = py::none())
      .def("run", &PyOmniSim::Run, py::arg("commands") = py::none(), py::arg("frames") = 0)
      .def_property_readonly("truth", &PyOmniSim::Truth)
      .def_property_readonly("truth_velocity", &PyOmniSim::TruthVelocity)
      .def_property_readonly("observed", &PyOmniSim::Observed)
      .def_property_readonly("t", &PyOmniSim::time)
      .def_property_readonly("frame", &PyOmniSim::frame)
      .def_property_readonly("ball", &PyOmniSim::Ball)
      .def_property_readonly("robots", &PyOmniSim::robots)
      .def_property_readonly("backend", &PyOmniSim::backend);

  py::class_<PyArmSim>(m, "ArmSim", "An arm driven by torques from Python, with the model's delay")
      .def(py::init([](const PyArmModel& model, const std::string& backend, const py::handle& predictor) {
             return std::make_unique<PyArmSim>(model.model, backend, predictor);
           }),
           py::arg("model"), py::arg("backend") = "analytic", py::arg("predictor") = py::none())
      .def("reset", &PyArmSim::Reset, py::arg("q") = py::none(), py::arg("qd") = py::none())
      .def("step", &PyArmSim::Step, py::arg("tau"))
      .def("set_controller", [](PyArmSim& sim, const std::string& kind, const PyArmModel& hat, double bandwidth,
                                double damping, bool friction) {
        sim.SetController(kind, hat.model, bandwidth, damping, friction);
      }, py::arg("kind"), py::arg("hat"), py::arg("bandwidth") = 10.0, py::arg("damping") = 1.0,
         py::arg("friction") = true)
      .def("step_reference", &PyArmSim::StepReference, py::arg("q_r"), py::arg("qd_r"), py::arg("qdd_r"))
      .def_property_readonly("q", &PyArmSim::q)
      .def_property_readonly("qd", &PyArmSim::qd)
      .def_property_readonly("t", &PyArmSim::time)
      .def_property_readonly("dof", &PyArmSim::dof)
      .def_property_readonly("sample_time", &PyArmSim::sample_time);

  m.def("_replay_omni", [](const PyOmniModel& model, const py::handle& log, const std::string& backend, int horizon,
                           const py::handle& predictor, const std::string& state) {
    return ReplayOmni(model.model, log, backend, horizon, predictor, state);
  });
  m.def("_model_robot", [](const std::string& path) { return ModelFileRobot(path); });
  m.def("_replay_arm", [](const PyArmModel& model, const py::handle& log) { return ReplayArm(model.model, log); });
  m.def("_training_data", [](const PyOmniModel& model, const py::handle& logs, int horizon) {
    return OmniTrainingData(model.model, logs, horizon);
  });
  m.def("_train_omni", [](const PyOmniModel& model, const py::handle& logs, const std::string& kind, int horizon,
                          bool residual, const std::string& nominal_engine, std::uint64_t seed, int epochs,
                          std::vector<int> hidden) {
    return TrainOmni(model.model, logs, kind, horizon, residual, nominal_engine, seed, epochs, std::move(hidden));
  });
  m.def("_train_arm", [](const PyArmModel& model, const py::handle& logs, const std::string& kind, bool residual,
                         std::uint64_t seed, int epochs, std::vector<int> hidden) {
    return TrainArm(model.model, logs, kind, residual, seed, epochs, std::move(hidden));
  });
  m.def("_identify", [](const PyArmModel& model, const py::handle& logs) {
    return PyArmModel{IdentifyArm(model.model, ToArmLogs(logs), WlsIdentificationOptions{})};
  });
  m.def("_diagnose", &Diagnose);
  m.def("_compare", [](const PyOmniModel& model, const py::handle& log, std::vector<std::string> backends,
                       const py::handle& predictor) { return Compare(model.model, log, std::move(backends), predictor); });
  m.def("_tune_pid", &TunePidFunction);
  m.def("_batch", &BatchFunction);
  m.def("_ilc", &IlcFunction);
  m.def("_run_arm_scene", &RunArmSceneFunction);
  m.def("available_backends", [](const std::string& robot) {
    return robot == "arm" ? AvailableArmBackends() : AvailableOmniBackends();
  }, py::arg("robot") = "omni");
}
