// `twinsim train --model MODEL --log LOG.csv [--log ...] --kind linear|mlp --horizon H --out P`
// [--residual [--nominal-engine E] [--nominal-state observer|tracker|auto] [--nominal-errors on|off]]
// (arms also: --history N)
#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>

#include "analysis/learned_noise.h"
#include "analysis/omni_replay.h"
#include "app/commands/commands.h"
#include "core/engine_names.h"
#include "core/error.h"
#include "core/progress.h"
#include "engines/omni_engine.h"
#include "io/atomic_file.h"
#include "io/output_files.h"
#include "io/yaml_extends.h"
#include "learning/arm_predictor.h"
#include "learning/omni_predictor.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"

namespace twinsim {
namespace {

struct TrainCliOptions {
  std::string model;
  std::vector<std::string> logs;
  std::string out;
  OmniTrainOptions train;
  int history = 4;     // arm only: samples of history
  bool history_given = false;
  bool residual = false;                // learn the correction to the nominal model
  std::optional<bool> nominal_errors;   // residual only: its recent errors as inputs
  std::optional<std::string> nominal_engine;  // omni residual only
  std::optional<int> nominal_substeps;         // omni residual only
  std::optional<int> nominal_state;  // omni residual only: an OmniReplayState, or 2 for auto
  bool quiet = false;
  bool no_noise = false;   // omni, one frame ahead: skip the driving noise's fit
  bool no_safeguard = false;  // omni, with the noise: skip its intervals' safeguard
  bool no_weight_uncertainty = false;  // omni, linear, one frame ahead: write none (the noise fitted alone)
  OmniLogSelector select;  // omni logs holding several robots
};

int TrainArm(const TrainCliOptions& options) {
  // Read and check everything before training or writing.
  const ArmModel model = LoadArmModel(options.model);
  std::vector<ArmLog> logs;
  for (const auto& path : options.logs) {
    logs.push_back(ReadArmLog(path));
    CheckArmLogMatchesModel(logs.back(), model);
  }
  ArmTrainOptions train;
  train.kind = options.train.kind;
  train.horizon = options.train.horizon;
  train.history = options.history;
  train.mlp = options.train.mlp;
  train.residual = options.residual;
  if (options.nominal_errors && !options.residual)
    throw InputError("--nominal-errors is for residual predictors only (add --residual)");
  train.nominal_errors = options.nominal_errors;
  if (options.nominal_engine || options.nominal_substeps || options.nominal_state)
    throw InputError("--nominal-engine, --nominal-substeps and --nominal-state are for omni robots (an arm's nominal "
                     "step runs on the analytic model)");
  if (options.train.members != 1) throw InputError("--members is for omni robots");
  if (std::string problem; !train.IsValid(&problem)) throw InputError(problem);

  const std::string what = (train.residual ? "residual " : "") + train.kind;
  Progress progress("train arm " + what, !options.quiet);
  ArmTrainSummary summary;
  const ArmPredictor predictor =
      TrainArmPredictor(model, logs, train, &summary, [&](int epoch, int epochs, double validation_mse) {
        char detail[64];
        std::snprintf(detail, sizeof detail, "epoch %d, validation mse %.4g", epoch, validation_mse);
        progress.Update(epoch, epochs, detail);
      });
  progress.Finish();
  OutputFiles files;
  predictor.Save(options.out);
  files.Add(options.out);
  if (!options.quiet) {
    std::printf("%s predictor of arm %s (%d joints)%s, %d sample(s) ahead at %g s: %s\n", what.c_str(),
                model.name.c_str(), model.dof(),
                train.residual ? (predictor.layout().nominal_errors ? ", over its nominal model, with its recent errors"
                                                                    : ", over its nominal model")
                               : "",
                train.horizon, model.sample_time, summary.BriefReport().c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

// What a one-frame predictor's rollouts are uncertain by: its driving noise and the
// safeguard of its intervals, each where fitted.
struct LearnedUncertainty {
  std::optional<LearnedNoiseFit> noise;
  OmniIntervalSafeguard safeguard;
};

// A one-frame predictor drives the learned backend: its driving noise, from the rows it
// was validated on (analysis/learned_noise.h), then the safeguard of the noise's
// intervals on the same rows (docs/learning.md, "The intervals' safeguard"), both set on
// *predictor, unless the options skip them.
LearnedUncertainty FitLearnedUncertainty(const OmniModel& model, const std::vector<OmniLog>& logs,
                                         const OmniTrainOptions& train, const TrainCliOptions& options,
                                         OmniPredictor* predictor) {
  LearnedUncertainty out;
  if (train.horizon != 1 || options.no_noise) return out;
  const std::vector<OmniLog> held_out = OmniValidationParts(logs, train.validation_fraction);
  if (!LongEnoughForLearnedNoise(held_out)) {
    // Said even with --quiet: the predictor then draws the model's noise, not its own.
    std::fprintf(stderr,
                 "train: warning: the driving noise is not fitted: the held-out rows (the last %g %% of each log) "
                 "are too short for a prediction %d frames ahead after the tracker's %d-frame warm-up; the learned "
                 "backend will draw the model's driving noise\n",
                 100 * train.validation_fraction, LearnedNoiseOptions{}.horizons.back(), kWarmUpFrames);
    return out;
  }
  Progress noise_progress("driving noise", !options.quiet);
  out.noise = FitLearnedDrivingNoise(model, *predictor, held_out, {},
                                     [&](int done, int total) { noise_progress.Update(done, total); });
  noise_progress.Finish();
  predictor->SetDrivingNoise(out.noise->noise);
  if (!options.no_safeguard) {
    out.safeguard = FitLearnedIntervalSafeguard(model, *predictor, held_out);
    predictor->SetIntervalScale(out.safeguard.Scales());
  }
  return out;
}

// The training's progress per epoch; an ensemble's members come one after another, their
// epochs counted as one run and the detail naming the member.
std::function<void(int, int, double)> EpochProgress(Progress* progress, const OmniTrainOptions& train) {
  return [progress, members = train.members, per = std::max(1, train.mlp.max_epochs)](int epoch, int epochs,
                                                                                      double validation_mse) {
    char detail[80];
    if (members > 1)
      std::snprintf(detail, sizeof detail, "network %d of %d, epoch %d, validation mse %.4f", (epoch - 1) / per + 1,
                    members, (epoch - 1) % per + 1, validation_mse);
    else
      std::snprintf(detail, sizeof detail, "epoch %d, validation mse %.4f", epoch, validation_mse);
    progress->Update(epoch, epochs, detail);
  };
}

int Train(const TrainCliOptions& options) {
  CheckFileCanBeWritten(options.out);  // before minutes of training, not after
  if (ModelFileRobot(options.model) == RobotKind::kArm) return TrainArm(options);
  if (options.history_given) throw InputError("--history is for arm models only (the omni layout is fixed)");
  if ((options.nominal_errors || options.nominal_engine || options.nominal_substeps || options.nominal_state) &&
      !options.residual)
    throw InputError("--nominal-engine, --nominal-substeps, --nominal-state and --nominal-errors are for residual "
                     "predictors only (add --residual)");
  // Read and check everything before training or writing.
  const OmniModel model = LoadOmniModel(options.model);
  std::vector<OmniLog> logs;
  for (const auto& path : options.logs) logs.push_back(ReadOmniLogSayingHoles(path, options.select));
  OmniTrainOptions train = options.train;
  train.residual = options.residual;
  if (options.nominal_engine) train.nominal_engine = *options.nominal_engine;
  if (options.nominal_substeps) train.nominal_substeps = *options.nominal_substeps;
  // Unless told, both states are trained and the held-out rollouts choose (auto).
  train.choose_nominal_state = !options.nominal_state || *options.nominal_state == 2;
  if (!train.choose_nominal_state) train.nominal_state = static_cast<OmniReplayState>(*options.nominal_state);
  if (options.nominal_errors) train.nominal_errors = *options.nominal_errors ? 5 : 0;
  if (std::string problem; !train.IsValid(&problem)) throw InputError(problem);
  if (train.residual) {
    const std::vector<std::string> built = AvailableOmniEngines();
    if (std::find(built.begin(), built.end(), train.nominal_engine) == built.end())
      throw InputError("--nominal-engine " + train.nominal_engine + " is not compiled into this build");
  }

  const std::string what = (train.residual ? "residual " : "") + train.kind;
  Progress progress("train " + what, !options.quiet);
  OmniTrainSummary summary;
  const OmniPredictor predictor = TrainOmniPredictor(model, logs, train, &summary, EpochProgress(&progress, train));
  progress.Finish();
  // Logs are pooled: one too short or too lossy to fill a window adds none. Said even
  // with --quiet: the predictor did not learn from it.
  for (const OmniLog& log : logs) {
    const std::vector<std::string>& used = predictor.info().logs;
    if (std::find(used.begin(), used.end(), log.path) == used.end())
      std::fprintf(stderr, "train: note: %s gave no complete window and was left out\n", log.path.c_str());
  }
  OmniPredictor written = predictor;
  if (options.no_weight_uncertainty) written.SetWeightUncertainty({});  // before the noise: fitted without it
  const LearnedUncertainty uncertainty = FitLearnedUncertainty(model, logs, train, options, &written);
  OutputFiles files;
  written.Save(options.out);
  files.Add(options.out);
  if (!options.quiet) {
    const std::string over = train.residual ? ", over its Newtonian model on " + train.nominal_engine +
                                                  (train.nominal_errors > 0 ? " with its recent errors" : "")
                                            : "";
    std::printf("%s predictor of %s%s, %d frame(s) ahead at %g fps: %s\n", what.c_str(), model.name.c_str(),
                over.c_str(), train.horizon, predictor.info().frame_rate, summary.BriefReport().c_str());
    if (const RidgeWeightUncertainty& u = written.weight_uncertainty(); !u.directions.empty()) {
      std::printf("weights' own uncertainty: %zu directions holding %.1f %% of the fit's covariance, from its residuals "
                  "in %d blocks of a second (each sampled rollout draws them; docs/learning.md)\n",
                  u.directions.size(), 100 * u.share, u.blocks);
    }
    if (const std::size_t more = written.ensemble().size(); more > 0) {
      std::printf("an ensemble of %zu networks, the first on the training windows, the others each on a bootstrap of "
                  "them by the second (each sampled rollout draws one; docs/learning.md)\n",
                  more + 1);
    }
    if (const auto& noise = uncertainty.noise) std::printf("on the held-out rows, %s", FormatLearnedNoiseFit(*noise).c_str());
    if (const OmniIntervalSafeguard& safeguard = uncertainty.safeguard; !safeguard.on.empty()) {
      std::printf("intervals' safeguard (a conformal scale of the rollouts' spread, fitted on the %s; each fold with "
                  "the others' scale, its share in the 90 %% regions without -> with it):\n%s",
                  safeguard.on.c_str(), FormatSafeguard(safeguard, logs.front().frame_period).c_str());
    }
    files.PrintWrote();
  }
  return kExitOk;
}

// The options of what a predictor knows of its own uncertainty: its driving noise, the
// intervals' safeguard, a linear predictor's weights' directions, a network's ensemble.
void AddUncertaintyOptions(CLI::App* cmd, TrainCliOptions* options) {
  cmd->add_flag("--no-noise", options->no_noise,
                "Omni, one frame ahead: do not fit the learned backend's driving noise on the held-out rows "
                "(docs/learning.md); the predictor then draws the model's");
  cmd->add_flag("--no-safeguard", options->no_safeguard,
                "Omni, with the driving noise: do not fit its intervals' safeguard (a conformal scale of the rollouts' "
                "spread per horizon, on the held-out rows; docs/learning.md)");
  cmd->add_flag("--no-weight-uncertainty", options->no_weight_uncertainty,
                "Omni, linear, one frame ahead: do not write the weights' own uncertainty (weight_uncertainty, "
                "drawn once per sampled rollout; docs/learning.md); the driving noise is then fitted without it");
  cmd->add_option("--members", options->train.members,
                  "Omni, --kind mlp, one frame ahead: train this many networks, the others each on a bootstrap of "
                  "the training windows by the second; each sampled rollout draws one (docs/learning.md)")
      ->capture_default_str();
}

}  // namespace

void AddTrainCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<TrainCliOptions>();
  CLI::App* cmd = app.add_subcommand("train", "Learn a predictor of a robot's motion from measured logs.");
  cmd->footer(
      "Inputs: the last 6 frames (pose relative to the newest in its robot frame, heading as sin and\n"
      "cos, the command acting then: 42 numbers), plus the commands acting during the horizon when\n"
      "H > 1. Output: the pose H frames ahead. The last 20 % of every log is held out for validation.\n"
      "Use the result with 'run --backend learned --predictor P' (H = 1), or in a go_to_pose scene.\n"
      "Arms (URDF, or YAML with 'robot: arm'; logs t,q1..qn,tau1..taun[,qd..]): the last --history\n"
      "samples of joint positions (sin, cos for revolute joints), velocities and the torques acting\n"
      "then (the logged command, delay_samples later); output: the joint state H samples ahead.\n"
      "--residual: learn only the correction to the model file's own prediction (omni: the Newtonian\n"
      "robot on --nominal-engine, carried along the log by its observer or the open-loop tracker,\n"
      "--nominal-state, by default whichever rolls out nearer on the held-out rows; arms: the\n"
      "one-sample step, rigid-body\n"
      "dynamics with its friction); --nominal-errors on|off adds that model's recent errors to the\n"
      "inputs (omni: its last 5 one-frame errors, default off; arms: over the history, default on for\n"
      "linear, off for mlp). A residual predictor works only with the model file it was trained over.\n"
      "See docs/learning.md and docs/arm_learning.md.");
  cmd->add_option("--model", options->model, "The robot's model file (its name and delay go into the predictor)")
      ->required();
  cmd->add_option("--log", options->logs, "Measured log(s) in the contract's format (repeat --log)")->required();
  cmd->add_option("--kind", options->train.kind, "linear (ridge regression) or mlp (neural net)")
      ->capture_default_str()
      ->check(CLI::IsMember({"linear", "mlp"}));
  cmd->add_option("--horizon", options->train.horizon, "H, frames ahead")->capture_default_str();
  cmd->add_option("--out", options->out, "Predictor file to write")->required();
  cmd->add_option("--history", options->history, "Arms only: samples of history in the inputs")
      ->capture_default_str()
      ->each([options](const std::string&) { options->history_given = true; });
  cmd->add_flag("--residual", options->residual,
                "Predict the model's own motion plus a learned correction (hybrid)");
  cmd->add_option_function<std::string>(
         "--nominal-errors",
         [options](const std::string& v) { options->nominal_errors = v == "on"; },
         "With --residual: the nominal model's recent errors as inputs (on|off)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option_function<std::string>(
         "--nominal-engine", [options](const std::string& v) { options->nominal_engine = v; },
         "Omni, with --residual: the engine of the model it corrects (analytic, ode, bullet; default analytic)")
      ->check(CLI::IsMember(KnownEngines()));
  cmd->add_option_function<int>(
      "--nominal-substeps", [options](const int& v) { options->nominal_substeps = v; },
      "Omni, with --residual: physics steps per frame of the model it corrects (default: a fifth of the "
      "loop's on analytic, 2 at 30 fps; the loop's on ode and bullet)");
  cmd->add_option_function<std::string>(
         "--nominal-state",
         [options](const std::string& v) {  // the word's index, from EnumWords
           options->nominal_state = std::stoi(v);
         },
         "Omni, with --residual: how the model it corrects is carried along the poses: observer (its Kalman "
         "filter: the estimate replay predicts from), tracker (moved to each pose, its velocity its own), or "
         "auto (both trained, the one whose held-out 1 s rollouts come nearer kept)")
      ->type_name("TEXT")
      ->transform(EnumWords({kOmniReplayStateWords[0], kOmniReplayStateWords[1], "auto"}))
      ->default_str("auto");
  cmd->add_option("--seed", options->train.mlp.seed, "Seed of the neural net's initialisation and batches")
      ->capture_default_str();
  cmd->add_option("--epochs", options->train.mlp.max_epochs, "Most epochs of neural-net training (1 to 1000000)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--hidden", options->train.mlp.hidden, "Hidden layer widths of the neural net (e.g. --hidden 64 64)")
      ->capture_default_str()
      ->expected(1, 8);
  cmd->add_option("--patience", options->train.mlp.patience, "Epochs without held-out improvement before stopping")
      ->capture_default_str();
  AddUncertaintyOptions(cmd, options.get());
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  AddLogSelectorOptions(cmd, &options->select);
  cmd->callback([options, exit_code] { *exit_code = Train(*options); });
}

}  // namespace twinsim
