// `twinsim replay --model MODEL --log LOG.csv --out OUT.csv [--backend B] [--horizon K]`
#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "analysis/arm_replay.h"
#include "analysis/omni_calibration.h"
#include "analysis/omni_calibration_report.h"
#include "analysis/omni_replay.h"
#include "app/commands/commands.h"
#include "core/error.h"
#include "core/progress.h"
#include "identification/wls_identification.h"
#include "identification_omni/omni_identification.h"
#include "io/output_files.h"
#include "io/printf_number.h"
#include "io/yaml_extends.h"
#include "io/yaml_reader.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "sim/omni_backend.h"

namespace twinsim {
namespace {

struct ReplayOptions {
  std::string model;
  std::string log;
  std::string out;
  std::string backend;  // "": the engine the model was fitted on, else ode
  int horizon = 4;
  OmniReplayState state = OmniReplayState::kObserver;
  std::string predictor;
  std::string cutoff = "10";  // arms: Hz, or auto (AddDerivativeCutoffOption)
  int samples = 0;             // omni: draws per row (0: the mean only)
  long long seed = 1;          // their stream
  std::string parameter_uncertainty = "on";  // omni, with samples: the parameters' covariance too
  bool quiet = false;
  OmniLogSelector select;  // omni logs holding several robots
};

// An arm: the commands the model needs for the logged motion (inverse dynamics with
// friction, the effects inverted, the delays shifted: PredictArmCommands).
int ReplayArm(const ReplayOptions& options) {
  if (options.samples > 0) throw InputError("--samples is for omni robots: an arm replay writes the model's torques");
  const ArmModel model = LoadArmModel(options.model);
  std::string cutoff_brief;
  const ArmLog log = ReadArmLogsAtCutoff({options.log}, options.cutoff, model, {}, nullptr, &cutoff_brief).front();
  ArmCommandSummary what;
  const Eigen::MatrixXd tau = PredictArmCommands(model, log, &what);
  OutputFiles files;
  WriteArmTorqueCsv(options.out, log.t, tau);
  files.Add(options.out);
  if (!options.quiet) {
    if (!cutoff_brief.empty()) std::printf("%s\n", cutoff_brief.c_str());
    const TorqueErrors e = CompareArmTorques(model, log, tau);
    const int effects = static_cast<int>(ListArmEffects(model.effects).size());
    std::printf("replayed %d rows of %s through %s (inverse dynamics with friction, %d effect(s)%s%s)\n", log.rows(),
                options.log.c_str(), model.name.c_str(), effects,
                what.shift.maxCoeff() > 0 ? ", commands sent ahead by the delays" : "",
                log.qd_logged && log.qdd_logged ? "" : ", qd/qdd derived from q");
    for (int j = 0; j < log.dof; ++j) {
      if (what.beyond_saturation[j] > 0)
        std::printf("joint %d: %d row(s) need more than its torque_saturation limit (written unclipped)\n", j + 1,
                    what.beyond_saturation[j]);
    }
    std::printf("joint  torque RMS  error RMS  relative\n");
    for (int j = 0; j < log.dof; ++j)
      std::printf("%5d  %10.4g  %9.4g  %7.2f %%\n", j + 1, e.torque_rms[j], e.error_rms[j], 100 * e.relative[j]);
    files.PrintWrote();
  }
  return kExitOk;
}

// How well the samples' distribution holds the log's measured poses (issue 64): the
// calibration compare prints, at the replay's one horizon, as a whole and by quarter of
// the log's turn rate. Nothing without measured rows.
std::string SampleCoverage(const OmniLog& log, const OmniReplayResult& result, int horizon) {
  const std::vector<PredictiveError> rows = PredictiveErrors(log, result, {}, horizon);
  if (rows.empty()) return "";
  OmniCalibration c = Calibrate(rows, ConstantSpread(rows));
  c.frames = horizon;
  c.seconds = horizon * log.frame_period;
  return "calibration of the samples' distribution on the log's measured poses (a calibrated model holds 50 % and "
         "90 %; energy score against the best constant spread on these rows):\n" +
         FormatCalibrationTable({c}) +
         "by quarter of the log's turn rate over each prediction (rad/s: position 50 / 90 % ellipses hold):\n" +
         FormatTurnRateCalibrationTable(CalibrateRowsByTurnRate({rows}, {horizon}, log.frame_period));
}

// Above this share of rows off the fitted engine's regions, a warning (below, a note).
constexpr double kEngineShare = 0.1;

// Samples drawn on an engine the model was not fitted on (issue 64): the share of
// predicted rows whose position lies outside the 90 % region of the fitted engine's
// prediction (with the camera's noise, as a measured pose is scored). Above
// kEngineShare the fan is drawn around another mean than the response the model was
// fitted to.
std::string EngineAgainstItsFit(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& asked,
                                const OmniReplayResult& result, bool* warn) {
  OmniReplayOptions o = asked;
  o.backend = model.fitted_on;
  o.covariance = true;
  if (o.state == OmniReplayState::kObserver) o.samples = 0;  // the filter's covariance needs no draws (the tracker's does)
  const OmniReplayResult fitted = ReplayOmniLog(model, log, o);
  const double chi2_90 = -2 * std::log(0.1);  // two dimensions
  int rows = 0, outside = 0;
  for (std::size_t i = 0; i < result.pose.size() && i < fitted.pose.size(); ++i) {
    if (!result.predicted[i] || !fitted.predicted[i] || i >= fitted.covariance.size()) continue;
    const Eigen::Vector2d d(result.pose[i].x - fitted.pose[i].x, result.pose[i].y - fitted.pose[i].y);
    // The region a measured pose is scored against: the prediction's and the camera's.
    const Eigen::LDLT<Eigen::Matrix2d> c(fitted.covariance[i].topLeftCorner<2, 2>() +
                                         fitted.measurement_covariance.topLeftCorner<2, 2>());
    if (c.info() != Eigen::Success || !c.isPositive()) continue;
    ++rows;
    if (d.dot(c.solve(d)) > chi2_90) ++outside;
  }
  *warn = rows > 0 && outside > kEngineShare * rows;
  if (rows == 0) return "";
  return "on " + asked.backend + " the predicted positions lie outside the " + model.fitted_on +
         " engine's 90 % region (the engine " + model.name + " was fitted on) on " + std::to_string(outside) + " of " +
         std::to_string(rows) + " predicted rows (" + PrintfNumber("%.1f", 100.0 * outside / rows) + " %)" +
         (*warn ? ": the samples are drawn around another mean than the fitted response" : "");
}

int Replay(const ReplayOptions& options) {
  // Check everything before writing anything.
  std::error_code same_error;
  if (std::filesystem::equivalent(options.out, options.log, same_error))
    throw InputError("--out " + options.out + " is the log being replayed (--log " + options.log +
                     "): the replay would overwrite it; give another file");
  if (ModelFileRobot(options.model) == RobotKind::kArm) return ReplayArm(options);
  const OmniModel model = LoadOmniModel(options.model);
  const OmniLog log = ReadOmniLogSayingHoles(options.log, options.select);
  OmniReplayOptions replay;
  std::string engine_note;
  replay.backend = ReplayEngineFor(model, options.backend, "ode", &engine_note);
  // Said even with --quiet: the predictions are not those of the engine the model was fitted on.
  if (!engine_note.empty()) std::fprintf(stderr, "note: %s\n", engine_note.c_str());
  replay.horizon = options.horizon;
  replay.state = options.state;
  replay.samples = options.samples;
  replay.seed = static_cast<std::uint64_t>(options.seed);
  replay.parameter_draws = options.parameter_uncertainty == "on";  // a linear predictor's weights
  if (options.samples > 0 && options.parameter_uncertainty == "on") {
    replay.parameter_shifts = ParameterShiftedModels(model, log.frame_period);
    replay.parameter_backend = ReplayEngineFor(model, "", "analytic");
  }
  if (std::string why; !replay.IsValid(&why)) throw InputError(why);
  if (!options.predictor.empty())
    replay.backend_options.predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(options.predictor));

  Progress progress("replay", !options.quiet);
  OmniReplayResult result = ReplayOmniLog(model, log, replay, [&](int done, int total) { progress.Update(done, total); });
  progress.Finish();
  if (const std::string grip = DescribeGrip(result.grip); !grip.empty()) {
    // Said even with --quiet: the predictions there are the model's outside its validity.
    std::fprintf(stderr, "warning: %s\n", grip.c_str());
  }
  if (result.bounded_steps > 0) {
    // Said even with --quiet: the predictions there are the bounds', not the predictor's.
    std::fprintf(stderr,
                 "warning: the learned predictor left the range of its training data on %ld steps; each was held to "
                 "%.1fx the largest step it was trained on\n",
                 result.bounded_steps, kBoundFactor);
  }
  if (result.unseen_input_steps > 0) {
    std::fprintf(stderr,
                 "warning: on %ld steps the learned predictor's inputs (poses, speeds, commands) lay beyond anything in "
                 "its training data (by more than %.0f %% of their range): its predictions there are extrapolation\n",
                 result.unseen_input_steps, 100 * kInputMargin);
  }
  if (options.samples > 0 && !engine_note.empty()) {
    bool warn = false;
    const std::string against = EngineAgainstItsFit(model, log, replay, result, &warn);
    // A warning is said even with --quiet: the fan a user tunes against is off its fit.
    if (warn) {
      std::fprintf(stderr, "warning: %s\n", against.c_str());
    } else if (!against.empty() && !options.quiet) {
      std::printf("%s\n", against.c_str());
    }
  }
  OutputFiles files;
  if (options.samples > 0) {
    WritePoseSamplesCsv(options.out, result.t, result.samples);
  } else {
    WritePoseCsv(options.out, result.t, result.pose);
  }
  files.Add(options.out);

  if (!options.quiet) {
    std::printf(
        "replayed %zu rows of %s through %s on %s (K = %d, delay %d frames, state from the %s): %d predicted, position "
        "RMSE %.4f m\n",
        log.rows.size(), options.log.c_str(), model.name.c_str(), replay.backend.c_str(), options.horizon,
        result.delay_frames, result.state == "none" ? "first two rows" : result.state.c_str(), result.num_predicted(),
        PositionRmse(log, result));
    if (options.samples > 0) std::printf("%s", SampleCoverage(log, result, options.horizon).c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddReplayCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Replay a measured log through a model.");
  cmd->footer(
      "Omni robots: row i of OUT.csv (t,x,y,theta) is the model's prediction of frame i from the\n"
      "measured state K frames earlier and the logged commands since, with the model's delay.\n"
      "K = 0: one free run from the first row. Rows without enough history hold the measured pose.\n"
      "The measured state comes from the model's Kalman filter (--state observer: pose and velocity\n"
      "corrected at every measured frame, observer: block of the model file) or, for comparison, from\n"
      "the model's open-loop response with only its pose corrected (--state tracker; the learned\n"
      "backend always tracks so, its window of measured poses being its estimate).\n"
      "Arms (URDF, or YAML with 'robot: arm'): OUT.csv (t,tau1..taun) holds the model's torques for\n"
      "the logged motion (inverse dynamics with friction and the model's effects inverted: offsets\n"
      "subtracted, flexible joints' motors driven, commands sent ahead by delay_samples and\n"
      "time_delay; saturation is not inverted), one row per input row; qd/qdd are\n"
      "derived from q (zero-phase filter at --cutoff) where the log lacks them. --backend,\n"
      "--predictor and --horizon do not apply to arms.");
  cmd->add_option("--model", options->model, "Model file (omni: YAML; arm: URDF or YAML)")->required();
  cmd->add_option("--log", options->log,
                  "Measured log (omni: t,x,y,theta,vx_cmd,vy_cmd,omega_cmd; arm: t,q1..qn,tau1..taun[,qd..,qdd..])")
      ->required();
  cmd->add_option("--out", options->out, "Output CSV")->required();
  cmd->add_option("--backend", options->backend,
                  "Backend: ode, bullet, analytic or learned (default: the engine an omni model was fitted on, its "
                  "fitted_on, else ode)");
  cmd->add_option("--predictor", options->predictor, "1-frame predictor for --backend learned (from twinsim train)");
  cmd->add_option("--horizon", options->horizon, "K, frames predicted ahead (0: free run)")
      ->capture_default_str()
      ->check(NonNegativeNumber());
  cmd->add_option("--state", options->state, "Omni: how the measured state is estimated: observer or tracker")
      ->type_name("TEXT")
      ->transform(EnumWords({std::begin(kOmniReplayStateWords), std::end(kOmniReplayStateWords)}))
      ->default_str(OmniReplayStateName(options->state));
  AddDerivativeCutoffOption(cmd, &options->cutoff);
  cmd->add_option("--samples", options->samples,
                  "Omni: N draws per row, written as t,sample,x,y,theta. The observer's state: from its prediction "
                  "(its mean and covariance: the estimate's uncertainty, the driving noise and the process noise). "
                  "The tracker's (the learned backend's): N rollouts, each under its own draw of the driving noise "
                  "(the predictor's where it has one, else the model's); at most 10000")
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--seed", options->seed, "The samples' random seed")->capture_default_str()->check(NonNegativeNumber());
  AddParameterUncertaintyOption(cmd, &options->parameter_uncertainty);
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  AddLogSelectorOptions(cmd, &options->select);
  cmd->callback([options, exit_code] { *exit_code = Replay(*options); });
}

}  // namespace twinsim
