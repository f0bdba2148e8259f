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
#include "learning/arm_predictor.h"
#include "learning/omni_features.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "scene/ilc_scene.h"
#include "scene/scene.h"
#include "scene/scene_run.h"
#include "tuning/pid_tuning.h"
#include "python/array_logs.h"
#include "python/model_binding.h"
#include "python/observer_binding.h"
#include "python/simulation_binding.h"

namespace py = pybind11;

namespace twinsim {
namespace {

// ---- the command functions ---------------------------------------------------------

Array ReplayOmni(const OmniModel& model, const py::handle& log, const std::string& backend, int horizon,
                 const py::handle& predictor, const std::string& state) {
  const OmniLog l = ToOmniLog(log, "log");
  OmniReplayOptions options;
  options.backend = backend;
  options.horizon = horizon;
  options.backend_options.predictor = OmniPredictorArg(predictor);
  std::string why;
  if (!ParseOmniReplayState(state, &options.state, &why, "state") || !options.IsValid(&why)) throw InputError(why);
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
                                         const std::string& nominal_state, std::uint64_t seed, int epochs,
                                         std::vector<int> hidden) {
  OmniTrainOptions options;
  options.kind = kind;
  options.horizon = horizon;
  options.residual = residual;
  options.nominal_engine = nominal_engine;
  // "auto" (train's default): both tracks trained, the held-out rollouts choose.
  options.choose_nominal_state = nominal_state == "auto";
  std::string why;
  if (!options.choose_nominal_state && !ParseOmniReplayState(nominal_state, &options.nominal_state, &why, "nominal_state"))
    throw InputError(why + " (or auto)");
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

  BindModels(m);
  BindOmniObserver(m, [](const py::handle& model) { return model.cast<const PyOmniModel&>().model; });

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
      .def_property_readonly("nominal_state", [](const OmniPredictor& p) {
        return std::string(OmniReplayStateName(p.info().nominal_state));
      })
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
  BindSimulations(m);

  m.def("_replay_omni", [](const PyOmniModel& model, const py::handle& log, const std::string& backend, int horizon,
                           const py::handle& predictor, const std::string& state) {
    return ReplayOmni(model.model, log, backend, horizon, predictor, state);
  });
  m.def("_model_robot", [](const std::string& path) { return std::string(RobotKindName(ModelFileRobot(path))); });
  m.def("_replay_arm", [](const PyArmModel& model, const py::handle& log) { return ReplayArm(model.model, log); });
  m.def("_training_data", [](const PyOmniModel& model, const py::handle& logs, int horizon) {
    return OmniTrainingData(model.model, logs, horizon);
  });
  m.def("_train_omni", [](const PyOmniModel& model, const py::handle& logs, const std::string& kind, int horizon,
                          bool residual, const std::string& nominal_engine, const std::string& nominal_state,
                          std::uint64_t seed, int epochs, std::vector<int> hidden) {
    return TrainOmni(model.model, logs, kind, horizon, residual, nominal_engine, nominal_state, seed, epochs,
                     std::move(hidden));
  });
  m.def("_train_arm", [](const PyArmModel& model, const py::handle& logs, const std::string& kind, bool residual,
                         std::uint64_t seed, int epochs, std::vector<int> hidden) {
    return TrainArm(model.model, logs, kind, residual, seed, epochs, std::move(hidden));
  });
  m.def("_identify", [](const PyArmModel& model, const py::handle& logs) {
    return PyArmModel{IdentifyArmByLeastSquares(model.model, ToArmLogs(logs), WlsIdentificationOptions{})};
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
