// `twinsim diagnose --model MODEL --log LOG.csv [--log ...] --out DIR`
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands/commands.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "diagnosis/arm_diagnosis.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "identification/wls_identification.h"
#include "io/atomic_file.h"
#include "io/yaml_extends.h"
#include "render/renderer.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model_yaml_writer.h"

namespace twinsim {
namespace {

struct DiagnoseCliOptions {
  std::string model;
  std::vector<std::string> logs;
  std::string out;
  DiagnosisOptions diagnosis;
  std::string cutoff = "auto";  // arm: Hz, or auto (AddDerivativeCutoffOption)
  bool quiet = false;
  OmniLogSelector select;  // omni logs holding several robots
};

int Diagnose(const DiagnoseCliOptions& options) {
  std::string why;
  if (!options.diagnosis.IsValid(&why)) throw InputError(why);
  if (std::filesystem::exists(options.out) && !std::filesystem::is_directory(options.out)) {
    throw InputError("--out " + options.out + ": exists and is not a folder");
  }
  const RobotKind kind = ModelFileRobot(options.model);
  Progress progress("diagnose", !options.quiet);
  // The steps (identification, rounds of effects, the tables) are not known ahead: the
  // line shows the step and the time, not a bar.
  auto report_progress = [&](const std::string& what) {
    ThrowIfInterrupted();
    progress.Status(what);
  };

  DiagnosisReport report;
  std::string model_yaml;
  std::string comment = "Repaired by twinsim diagnose from " + options.model + " and";
  for (const auto& log : options.logs) comment += "\n  " + log;
  if (kind == RobotKind::kArm) {
    const ArmModel model = LoadArmModel(options.model);
    std::string cutoff_brief;
    const std::vector<ArmLog> logs =
        ReadArmLogsAtCutoff(options.logs, options.cutoff, model, {}, nullptr, &cutoff_brief);
    if (!options.quiet && !cutoff_brief.empty()) std::printf("%s\n", cutoff_brief.c_str());
    ArmModel repaired;
    report = DiagnoseArm(model, logs, options.diagnosis, &repaired, report_progress);
    if (!cutoff_brief.empty()) report.notes.insert(report.notes.begin(), "The logs' " + cutoff_brief + ".");
    if (!cutoff_brief.empty()) comment += "\n" + cutoff_brief;
    model_yaml = FormatArmModelYaml(repaired, comment + "\n" + DiagnosisVerdict(report));
  } else {
    const OmniModel model = LoadOmniModel(options.model);
    std::vector<OmniLog> logs;
    for (const auto& path : options.logs) logs.push_back(ReadOmniLogSayingHoles(path, options.select));
    OmniModel repaired;
    report = DiagnoseOmni(model, logs, options.diagnosis, &repaired, report_progress);
    model_yaml = FormatOmniModelYaml(repaired, comment + "\n" + DiagnosisVerdict(report));
  }
  progress.Finish();

  // Everything is computed before anything is written; each file is written atomically.
  const std::string json = FormatDiagnosisJson(report);
  const std::string html = FormatDiagnosisHtml(report, *MakeDefaultRenderer());
  const std::string dir = options.out;
  WriteFileAtomically(dir + "/model.yaml", model_yaml);
  WriteFileAtomically(dir + "/report.json", json);
  WriteFileAtomically(dir + "/report.html", html);
  if (!options.quiet) {
    std::printf("%s", FormatDiagnosisTable(report).c_str());
    std::printf("diagnosed in %.1f s; wrote %s/model.yaml, %s/report.json, %s/report.html\n", report.seconds, dir.c_str(),
                dir.c_str(), dir.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddDiagnoseCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<DiagnoseCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose", "Find where a model and measured logs disagree, name the missing effects, add them, show the gap shrink.");
  cmd->footer(
      "Replays the model over the logs (arm: the commands its inverse dynamics needs; omni: the\n"
      "4-frame prediction of replay), fits every effect of the contract's vocabulary on part of\n"
      "each log, scores it on time blocks held out from every fit, and adds effects one at a time\n"
      "while the held-out gap drops significantly. The model's own parameters and effects are\n"
      "trusted. Writes DIR/model.yaml (the repaired model), DIR/report.json and DIR/report.html.\n"
      "Exit 0 whether or not effects were found. Method and limits: docs/diagnose.md.");
  cmd->add_option("--model", options->model, "Model (arm: URDF or YAML; omni: YAML)")->required();
  cmd->add_option("--log", options->logs, "Measured log(s) in the contract's format (repeat --log)")->required();
  cmd->add_option("--out", options->out, "Folder for model.yaml, report.json and report.html")->required();
  cmd->add_option("--held-out", options->diagnosis.held_out, "Share of each log's time blocks held out from every fit")
      ->capture_default_str();
  cmd->add_option("--block", options->diagnosis.block_seconds,
                  "s, length of a time block; 0 = a 20th of the longest log, 0.5 to 10 s")
      ->capture_default_str();
  cmd->add_option("--max-effects", options->diagnosis.max_effects, "The most effects added")->capture_default_str();
  cmd->add_option("--min-improvement", options->diagnosis.min_improvement,
                  "Share of the selection rows' squared error an effect must remove to be added")
      ->capture_default_str();
  cmd->add_option("--alpha", options->diagnosis.alpha,
                  "Family-wise level of the tests (Holm over each round's candidates; the adequacy checks)")
      ->capture_default_str();
  cmd->add_option("--backend", options->diagnosis.backend,
                  "Omni: physics that replays the model (analytic, ode, bullet; default: the engine the model was "
                  "fitted on, its fitted_on, else analytic)");
  cmd->add_option("--horizon", options->diagnosis.horizon, "Omni: frames predicted ahead")->capture_default_str();
  cmd->add_option("--standstill", options->diagnosis.standstill,
                  "Arm: rad/s (m/s) below which a joint sticks, its friction anything up to the static level")
      ->capture_default_str();
  cmd->add_flag("--refit-model", options->diagnosis.refit_model,
                "Refit the model's own parameters on the fit blocks first (arm: inertial parameters and friction; "
                "omni: twinsim identify's delay, per-axis response and couplings). Default: trust them, so that "
                "an arm's payload is named, not absorbed");
  AddDerivativeCutoffOption(cmd, &options->cutoff);
  cmd->add_option("--threads", options->diagnosis.threads, "Worker threads (0: one per core); results do not depend on it")
      ->capture_default_str();
  cmd->add_flag("--quiet,-q", options->quiet, "No table and no progress");
  AddLogSelectorOptions(cmd, &options->select);
  cmd->callback([options, exit_code] { *exit_code = Diagnose(*options); });
}

}  // namespace twinsim
