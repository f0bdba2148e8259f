#include "python/simulation_binding.h"

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backends/arm_backend_factory.h"
#include "backends/omni_backend_factory.h"
#include "control/computed_torque.h"
#include "core/error.h"
#include "python/array_logs.h"
#include "python/model_binding.h"
#include "scene/scene.h"
#include "sim/arm_simulation.h"
#include "sim/omni_simulation.h"

namespace twinsim {
namespace {

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

}  // namespace

void BindSimulations(py::module_& m) {
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

}

}  // namespace twinsim
