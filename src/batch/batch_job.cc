#include "batch/batch_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <new>

#include "analysis/arm_replay.h"
#include "analysis/omni_compare.h"
#include "analysis/omni_replay.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/math_constants.h"
#include "engines/omni_engine.h"
#include "io/output_files.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/omni/omni_log.h"
#include "scene/arm_scene.h"
#include "scene/scene.h"
#include "scene/scene_run.h"

namespace twinsim {
namespace {

using Metrics = std::vector<std::pair<std::string, double>>;

// The job's parameters sorted into what the commands take.
struct JobInputs {
  std::string scene, model, log, predictor, backend;
  std::vector<std::string> backends;
  int horizon = 4;
  std::uint64_t seed = 0;
  SceneOverrides scene_overrides;  // scene.KEY and plant.KEY
  YamlOverrides model_overrides;   // model.KEY
};

JobInputs ReadInputs(const SweepJob& job) {
  JobInputs in;
  in.seed = job.seed;
  for (const auto& [name, value] : job.parameters) {
    if (name == "scene") in.scene = value.node.Scalar();
    if (name == "model") in.model = value.node.Scalar();
    if (name == "log") in.log = value.node.Scalar();
    if (name == "predictor") in.predictor = value.node.Scalar();
    if (name == "backend") in.backend = value.text;
    if (name == "horizon") in.horizon = std::stoi(value.text);
    if (name == "backends")
      for (const YAML::Node& b : value.node) in.backends.push_back(b.IsScalar() ? b.Scalar() : "?");
    if (name.rfind("scene.", 0) == 0) in.scene_overrides.scene.push_back({name.substr(6), value.node});
    if (name.rfind("plant.", 0) == 0) in.scene_overrides.plant.push_back({name.substr(6), value.node});
    if (name.rfind("model.", 0) == 0) in.model_overrides.push_back({name.substr(6), value.node});
  }
  return in;
}

std::string Indexed(const std::string& name, Eigen::Index j) { return name + "_" + std::to_string(j + 1); }

Metrics RunOmni(const Sweep& sweep, const JobInputs& in, OutputFiles* files) {
  Scene scene = LoadScene(in.scene, in.scene_overrides);
  scene.seed = in.seed;
  const std::string backend = in.backend.empty() ? scene.backend : in.backend;
  const SimulationResult result = RunOmniScene(scene, backend, in.predictor);
  WriteOmniRunFiles(scene, result, sweep.plots, files);
  const FrameRecord& last = result.frames[0].back();
  return {{"final_x", last.truth.x},
          {"final_y", last.truth.y},
          {"final_theta", last.truth.theta},
          {"path_length", TruePathLength(result, 0)}};
}

Metrics RunArm(const Sweep& sweep, const JobInputs& in, OutputFiles* files) {
  ArmScene scene = LoadArmScene(in.scene, in.scene_overrides);
  scene.seed = in.seed;
  const std::string backend = in.backend.empty() ? scene.backend : in.backend;
  const TrackingTrial trial = RunArmScene(scene, backend, in.predictor);
  WriteArmRunFiles(scene, trial, backend, sweep.plots, files);
  Metrics m;
  for (Eigen::Index j = 0; j < trial.error_rms.size(); ++j) {
    m.emplace_back(Indexed("rms_error", j), trial.error_rms[j]);
    m.emplace_back(Indexed("max_error", j), trial.error_max[j]);
    m.emplace_back(Indexed("saturated", j), trial.saturated_fraction[j]);
    m.emplace_back(Indexed("command_rms", j), trial.command_rms[j]);
  }
  return m;
}

// The log the job works on: given, or recorded by running its scene (on the scene's
// own backend: `scene.backend` sets it) into trajectory.csv.
std::string JobLog(const JobInputs& in, RobotKind kind, OutputFiles* files) {
  if (!in.log.empty()) return in.log;
  if (kind == RobotKind::kArm) {
    ArmScene scene = LoadArmScene(in.scene, in.scene_overrides);
    scene.seed = in.seed;
    WriteArmRunFiles(scene, RunArmScene(scene, scene.backend, ""), scene.backend, false, files);
  } else {
    Scene scene = LoadScene(in.scene, in.scene_overrides);
    scene.seed = in.seed;
    WriteOmniRunFiles(scene, RunOmniScene(scene, scene.backend, ""), false, files);
  }
  return files->Path("trajectory.csv");
}

Metrics Replay(const JobInputs& in, OutputFiles* files) {
  const RobotKind kind = ModelFileRobot(in.model);
  if (kind == RobotKind::kArm) {
    const ArmModel model = LoadArmModel(in.model, in.model_overrides);
    const ArmLog log = ReadArmLog(JobLog(in, kind, files));
    CheckArmLogMatchesModel(log, model);
    const Eigen::MatrixXd tau = PredictArmCommands(model, log);
    WriteArmTorqueCsv(files->Path("replay.csv"), log.t, tau);
    files->Add("replay.csv");
    const TorqueErrors e = CompareArmTorques(model, log, tau);
    Metrics m;
    for (Eigen::Index j = 0; j < e.error_rms.size(); ++j) {
      m.emplace_back(Indexed("torque_error_rms", j), e.error_rms[j]);
      m.emplace_back(Indexed("torque_relative", j), e.relative[j]);
    }
    return m;
  }
  const OmniModel model = LoadOmniModel(in.model, in.model_overrides);
  const OmniLog log = ReadOmniLog(JobLog(in, kind, files));
  OmniReplayOptions replay;
  replay.backend = ReplayEngineFor(model, in.backend, "ode");
  replay.horizon = in.horizon;
  if (!in.predictor.empty())
    replay.backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(in.predictor));
  const OmniReplayResult result = ReplayOmniLog(model, log, replay);
  WritePoseCsv(files->Path("replay.csv"), result.t, result.pose);
  files->Add("replay.csv");
  double heading = 0;
  int predicted = 0;
  for (std::size_t i = 0; i < result.t.size(); ++i) {
    if (!PredictedAndMeasured(log, result, i)) continue;
    const double d = std::remainder(result.pose[i].theta - log.rows[i].pose.theta, 2 * kPi);
    heading += d * d;
    ++predicted;
  }
  return {{"position_rmse", PositionRmse(log, result)},
          {"heading_rmse", predicted > 0 ? std::sqrt(heading / predicted) : 0.0},
          {"predicted", static_cast<double>(predicted)}};
}

std::string HorizonTag(int frames, double frame_rate) {
  if (frames == 0) return "free";
  if (frames == static_cast<int>(std::lround(frame_rate))) return "1s";
  return std::to_string(frames) + "f";
}

Metrics Compare(const JobInputs& in, OutputFiles* files) {
  const RobotKind kind = ModelFileRobot(in.model);
  if (kind != RobotKind::kOmni) throw InputError(SourceLocation{in.model}, "compare takes omni models (this one is an arm's)");
  const OmniModel model = LoadOmniModel(in.model, in.model_overrides);
  const OmniLog log = ReadOmniLog(JobLog(in, kind, files));
  const double frame_rate = 1.0 / log.frame_period;
  std::shared_ptr<const OmniPredictor> predictor;
  if (!in.predictor.empty()) predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(in.predictor));
  const OmniCompareResult result = CompareOmniLog(model, log, MakeCompareOptions(model, log, in.backends, predictor));
  files->Write("errors.csv", FormatCompareErrorsCsv(result));
  Metrics m;
  for (const CompareErrorRow& row : result.rows)
    m.emplace_back(row.source + "_" + HorizonTag(row.horizon_frames, frame_rate) + "_position_rmse", row.position_rmse);
  return m;
}

std::string OneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

void CheckSweepJobLoads(const Sweep& sweep, const SweepJob& job) {
  const JobInputs in = ReadInputs(job);
  try {
    if (!in.scene.empty()) {
      if (SceneRobotKind(in.scene) == RobotKind::kArm) {
        LoadArmScene(in.scene, in.scene_overrides);
      } else {
        LoadScene(in.scene, in.scene_overrides);
      }
    }
    if (!in.model.empty()) {
      if (ModelFileRobot(in.model) == RobotKind::kArm) {
        LoadArmModel(in.model, in.model_overrides);
      } else {
        LoadOmniModel(in.model, in.model_overrides);
      }
    }
  } catch (const InputError& e) {
    // The files loaded alone before the sweep was accepted, so the keys it sets are to
    // blame: point at the first of them.
    SourceLocation where{sweep.path};
    std::string keys;
    for (const auto* list : {&sweep.fixed, &sweep.grid, &sweep.random}) {
      for (const SweepParameter& p : *list) {
        if (p.name.find('.') == std::string::npos) continue;
        if (keys.empty()) where = p.where;
        keys += (keys.empty() ? "" : ", ") + p.name;
      }
    }
    throw InputError(where, "job " + job.id + " (the first) does not load with the sweep's parameters" +
                                (keys.empty() ? std::string() : " (it sets " + keys + ")") + ":\n" + e.what());
  }
  // A log every job replays (a fixed one) is read whole too: a bad cell fails the sweep
  // once, with its file and line, rather than every job. A swept log is each job's own
  // and fails alone, as other swept values do.
  const bool shared = std::any_of(sweep.fixed.begin(), sweep.fixed.end(),
                                  [](const SweepParameter& p) { return p.name == "log"; });
  if (shared && !in.log.empty() && !in.model.empty()) {
    if (ModelFileRobot(in.model) == RobotKind::kArm) {
      ReadArmLog(in.log);
    } else {
      ReadOmniLog(in.log);
    }
  }
}

JobResult RunSweepJob(const Sweep& sweep, const SweepJob& job, const std::string& folder) {
  JobResult r;
  r.index = job.index;
  r.id = job.id;
  const auto start = std::chrono::steady_clock::now();
  try {
    const JobInputs in = ReadInputs(job);
    OutputFiles files(folder);
    if (sweep.command == "run") {
      r.metrics = SceneRobotKind(in.scene) == RobotKind::kArm ? RunArm(sweep, in, &files) : RunOmni(sweep, in, &files);
    } else if (sweep.command == "replay") {
      r.metrics = Replay(in, &files);
    } else {
      r.metrics = Compare(in, &files);
    }
    r.status = "ok";
    for (const auto& [name, value] : r.metrics) {
      if (!std::isfinite(value)) throw CheckFailed("metric " + name + " is not finite");
    }
  } catch (const Interrupted&) {
    throw;  // not the job's failure: the sweep stops, and --resume runs the job again
  } catch (const InputError& e) {
    r.status = "failed";
    r.error = "bad input: " + OneLine(e.what());
  } catch (const CheckFailed& e) {
    r.status = "failed";
    r.error = "check failed: " + OneLine(e.what());
  } catch (const std::bad_alloc&) {
    r.status = "failed";
    r.error = "internal error: out of memory";
  } catch (const std::exception& e) {
    r.status = "failed";
    r.error = "internal error: " + OneLine(e.what());
  }
  if (r.status == "failed") r.metrics.clear();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace twinsim
