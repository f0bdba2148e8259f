#include "scene/scene_run.h"

#include <initializer_list>

#include <cmath>

#include "backends/arm_backend_factory.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "io/csv_table.h"
#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"
#include "render/renderer.h"
#include "robots/omni/omni_log.h"
#include "scene/scene_plots.h"

namespace twinsim {
namespace {

// The ground truth of one robot: true pose and velocity at every frame it is on the
// field (a frame off the field, SimRobot::present, has no row).
std::string TruthCsv(const std::vector<FrameRecord>& frames) {
  std::string out = kTruthHeader;
  for (const auto& f : frames) AppendTruthRow(f, &out);
  return out;
}

void AppendNumbers(std::initializer_list<double> values, std::string* out) {
  bool first = true;
  for (double v : values) {
    if (!first) *out += ',';
    *out += FormatCsvNumber(v);
    first = false;
  }
  *out += '\n';
}

}  // namespace

void AppendTruthRow(const FrameRecord& f, std::string* out) {
  if (!f.present) return;  // off the field: no true pose to log
  AppendNumbers({f.t, f.truth.x, f.truth.y, f.truth.theta, f.command.vx, f.command.vy, f.command.omega,
                 f.truth_velocity.vx, f.truth_velocity.vy, f.truth_velocity.omega},
                out);
}

void AppendObserverRow(const FrameRecord& f, std::string* out) {
  if (f.observed) AppendOmniLogRow(OmniLogRow{f.stamp, f.seen, f.command}, out);
}

void AppendBallRow(const BallRecord& b, std::string* out) {
  AppendNumbers({b.t, b.truth.position.x(), b.truth.position.y(), b.truth.position.z(), b.truth.velocity.x(),
                 b.truth.velocity.y(), b.truth.velocity.z()},
                out);
}

std::string BallCsv(const std::vector<BallRecord>& ball) {
  std::string out = kBallHeader;
  for (const BallRecord& b : ball) AppendBallRow(b, &out);
  return out;
}

namespace {

// What only the simulation knows, per sample and joint: the tracking error, the demand
// before clamping, the controller's model-based part, the drive torque applied and the
// torque the plant needed (TrackingTrial's columns).
std::string ArmTrackingCsv(const TrackingTrial& trial) {
  const Eigen::MatrixXd error = trial.q_ref - trial.q;
  return JointColumnsCsv(trial.t, {"error", "demand", "model", "applied", "needed"},
                         {&error, &trial.demand, &trial.model_torque, &trial.applied, &trial.needed});
}

}  // namespace

std::vector<OmniLogRow> ObserverLog(const std::vector<FrameRecord>& frames) {
  std::vector<OmniLogRow> rows;
  for (const auto& f : frames)
    if (f.observed) rows.push_back(OmniLogRow{f.stamp, f.seen, f.command});
  return rows;
}

SimulationResult RunOmniScene(const Scene& scene, const std::string& backend, const std::string& predictor,
                              const std::function<void(int, int)>& progress) {
  OmniBackendOptions backend_options;
  if (!predictor.empty()) backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(predictor));
  Simulation sim = MakeSimulation(scene, backend, backend_options);
  return sim.Run(scene.num_frames(), progress);
}

std::unique_ptr<ArmBackend> MakeArmSceneBackend(const ArmScene& scene, const std::string& backend,
                                                const std::string& predictor) {
  return MakeArmBackend(backend, scene.plant, ArmSceneBackendOptions(scene, backend, predictor));
}

ArmBackendOptions ArmSceneBackendOptions(const ArmScene& scene, const std::string& backend, const std::string& predictor) {
  ArmBackendOptions backend_options;
  if (backend == "learned") {
    if (predictor.empty()) {
      throw InputError(SourceLocation{scene.path},
                       "--backend learned needs --predictor P (an arm predictor from 'twinsim train')");
    }
    backend_options.predictor = std::make_shared<ArmPredictor>(ArmPredictor::Load(predictor));
  } else if (!predictor.empty()) {
    throw InputError("--predictor applies to --backend learned only; arm scene '" + scene.name + "' runs on " + backend);
  }
  // Build one now: a predictor that does not fit the scene's model is refused before any
  // trial runs.
  MakeArmBackend(backend, scene.plant, backend_options);
  return backend_options;
}

TrackingTrial RunArmScene(const ArmScene& scene, const std::string& backend, const std::string& predictor) {
  const ArmReference reference = ArmSceneReference(scene);
  std::unique_ptr<ArmBackend> engine = MakeArmSceneBackend(scene, backend, predictor);
  TrackingOptions tracking = scene.tracking;
  tracking.backend = backend;
  tracking.dither_seed = scene.seed;
  return RunTrackingTrial(scene.plant, std::move(engine), scene.hat, reference, tracking);
}

void WriteOmniRunFiles(const Scene& scene, const SimulationResult& result, bool plots,
                       OutputFiles* files) {
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    const std::string suffix = i == 0 ? "" : "_" + result.robot_names[i];
    WriteOmniLog(files->Path("trajectory" + suffix + ".csv"), ObserverLog(result.frames[i]));
    files->Add("trajectory" + suffix + ".csv");
    files->Write("truth" + suffix + ".csv", TruthCsv(result.frames[i]));
  }
  if (!result.ball.empty()) files->Write("ball.csv", BallCsv(result.ball));
  if (plots) WriteOmniRunPlots(scene, result, files);
}

void WriteOmniRunPlots(const Scene& scene, const SimulationResult& result, OutputFiles* files) {
  if (scene.plots.empty() || !RenderingCompiled()) return;
  std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
  // A mixed field's name lists every robot: too long for a title; the paths say each one's.
  const bool mixed = result.backend.rfind("mixed:", 0) == 0;
  for (const ScenePlot& plot : ScenePlots(scene, result, mixed ? "mixed backends" : result.backend))
    files->WritePng(plot.file, RenderScenePlot(plot, *renderer));
}

void WriteArmRunFiles(const ArmScene& scene, const TrackingTrial& trial, const std::string& backend, bool plots,
                      OutputFiles* files) {
  files->Write("trajectory.csv", ArmSceneTrajectoryCsv(scene, trial));
  files->Write("tracking.csv", ArmTrackingCsv(trial));
  if (plots && !scene.plots.empty() && RenderingCompiled()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    for (const ScenePlot& plot : ArmScenePlots(scene, trial, backend))
      files->WritePng(plot.file, RenderScenePlot(plot, *renderer));
  }
}

double TruePathLength(const SimulationResult& result, int robot) {
  double length = 0;
  const std::vector<FrameRecord>& frames = result.frames.at(robot);
  for (std::size_t i = 1; i < frames.size(); ++i)
    if (frames[i].present && frames[i - 1].present)
      length += std::hypot(frames[i].truth.x - frames[i - 1].truth.x, frames[i].truth.y - frames[i - 1].truth.y);
  return length;
}

}  // namespace twinsim
