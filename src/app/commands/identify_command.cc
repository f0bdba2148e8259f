// `twinsim identify --model MODEL --log LOG.csv [--log ...] --out MODEL_OUT`
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "analysis/arm_identification.h"
#include "analysis/arm_output_error.h"
#include "analysis/arm_replay.h"
#include "analysis/identification_validation.h"
#include "analysis/position_friction_choice.h"
#include "app/commands/commands.h"
#include "core/error.h"
#include "core/progress.h"
#include "identification/identification_csv.h"
#include "identification/wls_identification.h"
#include "io/output_files.h"
#include "io/yaml_extends.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "identification_omni/omni_identification.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model_yaml_writer.h"

namespace twinsim {
namespace {

struct IdentifyCliOptions {
  std::string model;
  std::vector<std::string> logs;
  std::vector<std::string> validate;
  std::string out;
  std::string report;
  std::string cutoff = "auto";  // Hz, or auto (AddDerivativeCutoffOption)
  WlsIdentificationOptions identification;
  bool unweighted = false;
  bool offsets = false;
  // The output-error refinement's windows in s, "run" for whole runs, "0" = none; a
  // comma-separated list is a continuation (each stage from where the last ended).
  std::string output_error = "0";
  double segment = ArmOutputErrorOptions{}.segment;  // s: with --output-error run, the shooting segments
  bool stribeck = false;    // with output_error: also try friction that holds at low speed
  std::string presliding;   // with output_error: lugre or maxwell, the Stribeck friction through bristles
  std::string position_friction = "0";  // knots along each joint's travel, or auto (0: one Coulomb level)
  std::string position_torque = "0";    // knots of a torque along each joint's travel, or auto (0: none)
  bool quiet = false;
  // Omni robots.
  OmniLogSelector select;
  OmniIdentificationOptions omni;
  std::vector<std::string> given;  // options given on the command line, for the checks per robot kind
};

// Measured torques of joint j against the a-priori and the identified model's.
SeriesPlot TorquePlot(const ArmLog& log, int j, const Eigen::MatrixXd& a_priori, const Eigen::MatrixXd& identified,
                      const std::string& model_name) {
  SeriesPlot plot;
  plot.title = model_name + ", joint " + std::to_string(j + 1) + ": " + std::filesystem::path(log.path).filename().string();
  plot.y_label = "torque [N m]";
  std::vector<double> t(log.t.data(), log.t.data() + log.rows());
  auto series = [&](const std::string& name, const Eigen::MatrixXd& m) {
    PlotSeries s;
    s.name = name;
    s.x = t;
    s.y.resize(t.size());
    for (int r = 0; r < log.rows(); ++r) s.y[static_cast<std::size_t>(r)] = m(r, j);
    plot.series.push_back(s);
  };
  series("measured", log.tau);
  series("a-priori model", a_priori);
  series("identified model", identified);  // its commands: with the offsets, when estimated
  return plot;
}

bool EndsWithYaml(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".yaml" || ext == ".yml";
}

// Omni: `--out DIR` writes DIR/model.yaml, report.json and report.html; `--out M.yaml`
// the model there and the reports into --report DIR when given.
int IdentifyOmniCli(const IdentifyCliOptions& options) {
  for (const char* arm_only : {"--offsets", "--unweighted", "--cutoff", "--decimate", "--max-condition",
                               "--output-error", "--stribeck", "--presliding", "--segment", "--position-friction",
                               "--position-torque"}) {
    if (std::find(options.given.begin(), options.given.end(), arm_only) != options.given.end())
      throw InputError(std::string(arm_only) + " is for arms; " + options.model + " is an omni robot");
  }
  std::string why;
  if (!options.omni.IsValid(&why)) throw InputError(why);
  const bool to_yaml = EndsWithYaml(options.out);
  if (!to_yaml && std::filesystem::exists(options.out) && !std::filesystem::is_directory(options.out))
    throw InputError("--out " + options.out + ": exists and is not a folder (give a folder, or a .yaml path for the model)");
  const OmniModel model = LoadOmniModel(options.model);
  std::vector<OmniLog> logs, validation;
  for (const auto& path : options.logs) logs.push_back(ReadOmniLogSayingHoles(path, options.select));
  for (const auto& path : options.validate) validation.push_back(ReadOmniLogSayingHoles(path, options.select));

  Progress progress("identify", !options.quiet);
  OmniModel identified;
  const OmniIdentificationReport report =
      IdentifyOmni(model, logs, validation, options.omni, &identified,
                   [&](int step, int steps, const std::string& what) { progress.Update(step, steps, what); });
  progress.Finish();

  std::string comment = "Identified by twinsim identify from " + options.model + " and";
  for (const auto& path : options.logs) comment += "\n  " + path;
  comment += "\nreport.json holds every parameter with its standard error.";
  const std::string yaml = FormatOmniModelYaml(identified, comment);
  const std::string json = FormatOmniIdentificationJson(report);
  const std::string report_dir = to_yaml ? options.report : options.out;
  std::string html;
  if (!report_dir.empty()) {
    if (RenderingCompiled()) {
      html = FormatOmniIdentificationHtml(report, *MakeDefaultRenderer());
    } else {
      std::fprintf(stderr, "identify: warning: report.html not written: %s\n", kRenderingNotCompiled);
    }
  }
  OutputFiles files;
  files.Write(to_yaml ? options.out : options.out + "/model.yaml", yaml);
  if (!report_dir.empty()) {
    files.Write(report_dir + "/report.json", json);
    if (!html.empty()) files.Write(report_dir + "/report.html", html);
  }
  if (!options.quiet) {
    std::printf("identified %s (omni) from %zu log(s) in %.1f s\n\n%s", model.name.c_str(), logs.size(), report.seconds,
                FormatOmniIdentificationTable(report).c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

// Whether identify refines by output error: over whole runs, or on windows (--output-error
// 0 sets none; a negative horizon reaches ArmOutputErrorOptions::IsValid's refusal).
bool RefinesByOutputError(const ArmOutputErrorOptions& o) { return o.whole_run || o.horizon != 0; }

// One stage's seconds ("0": none), `text` of the stage `item`; InputError for what is no
// number.
double ParseOutputErrorHorizon(const std::string& text, const std::string& item) {
  std::size_t used = 0;
  double seconds = 0;
  try {
    seconds = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size())
    throw InputError("--output-error " + item + ": give the windows' length in seconds (0.1, or 0.1+1 for both at "
                     "once), or run for whole runs");
  return seconds;
}

// --output-error's stages: "0" none, else each comma-separated item a window length in
// seconds or "run", each stage's options `base` with its horizon. InputError for an
// empty item, a 0 within a list, or one that is checked invalid.
std::vector<ArmOutputErrorOptions> ParseOutputErrorStages(const std::string& text, const ArmOutputErrorOptions& base) {
  std::vector<ArmOutputErrorOptions> stages;
  if (text == "0") return stages;
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = text.find(',', from);
    const std::string item = text.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    ArmOutputErrorOptions stage = base;
    stage.whole_run = item == "run";
    // "0.1+1": windows of 0.1 s and of 1 s fitted at once.
    const std::size_t plus = item.find('+');
    stage.horizon = stage.whole_run ? 0 : ParseOutputErrorHorizon(item.substr(0, plus), item);
    if (plus != std::string::npos && !(stage.horizon > 0))
      throw InputError("--output-error " + item + ": each length fitted at once must be above 0 s");
    for (std::size_t at = plus; at != std::string::npos;) {
      const std::size_t next = item.find('+', at + 1);
      const double seconds =
          ParseOutputErrorHorizon(item.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1), item);
      if (!(seconds > 0)) throw InputError("--output-error " + item + ": each length fitted at once must be above 0 s");
      stage.also_horizons.push_back(seconds);
      at = next;
    }
    std::string why;
    if (!RefinesByOutputError(stage))
      throw InputError("--output-error " + text + ": 0 (none) cannot be a stage of a continuation");
    if (!stage.IsValid(&why)) throw InputError("--output-error: " + why);
    stages.push_back(stage);
    if (comma == std::string::npos) return stages;
    from = comma + 1;
  }
}

// A --position-friction or --position-torque value: a whole number of knots, or 0 for
// auto (chosen later from the logs).
int KnotsOption(const char* flag, const std::string& text) {
  if (text == "auto") return 0;
  char* end = nullptr;
  const long knots = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || knots < 0 || knots > 1000)
    throw InputError(std::string(flag) + ": expected auto or a whole number of knots, got '" + text + "'");
  return static_cast<int>(knots);
}

// Refuses omni-only options, a non-YAML --out and bad settings; returns the weighted least squares' options.
WlsIdentificationOptions CheckArmIdentifyOptions(const IdentifyCliOptions& options,
                                                 std::vector<ArmOutputErrorOptions>* stages) {
  for (const char* omni_only :
       {"--held-out", "--block", "--horizon", "--backend", "--stride", "--max-delay", "--robot", "--team", "--state",
        "--no-noise", "--no-drift", "--no-turn-harmonics", "--safeguard"}) {
    if (std::find(options.given.begin(), options.given.end(), omni_only) != options.given.end())
      throw InputError(std::string(omni_only) + " is for omni robots; " + options.model + " is an arm");
  }
  if (!EndsWithYaml(options.out))
    throw InputError("--out " + options.out + ": the identified model is written as YAML; give a .yaml or .yml path");
  WlsIdentificationOptions identification = options.identification;
  identification.weighted = !options.unweighted;
  identification.torque_offsets = options.offsets;
  identification.position_friction_knots = KnotsOption("--position-friction", options.position_friction);
  identification.position_torque_knots = KnotsOption("--position-torque", options.position_torque);
  std::string why;
  if (!identification.IsValid(&why)) throw InputError(why);
  ArmOutputErrorOptions base;
  base.segment = options.segment;
  base.offsets = options.offsets;
  base.stribeck = options.stribeck || !options.presliding.empty();
  base.presliding = options.presliding == "lugre"     ? ArmPresliding::kLugre
                    : options.presliding == "maxwell" ? ArmPresliding::kMaxwellSlip
                                                      : ArmPresliding::kNone;
  base.threads = options.omni.threads;
  base.rest_share = identification.rest_share;
  *stages = ParseOutputErrorStages(options.output_error, base);
  const bool refine = !stages->empty();
  const bool whole_run = std::any_of(stages->begin(), stages->end(), [](const auto& s) { return s.whole_run; });
  if (!whole_run && std::find(options.given.begin(), options.given.end(), "--segment") != options.given.end())
    throw InputError("--segment cuts --output-error run's whole runs: give --output-error run as well");
  if (options.stribeck && !refine)
    throw InputError("--stribeck refines by output error: give --output-error S as well");
  if (!options.presliding.empty() && !refine)
    throw InputError("--presliding refines by output error: give --output-error S as well");
  if (options.omni.threads < 0) throw InputError("--threads must be 0 (one per core) or more");
  return identification;
}

// One output-error stage's lines of the model file's comment; `presliding` the option's text.
std::string RefinementComment(const ArmOutputErrorSummary& refinement, const std::string& presliding) {
  std::string comment;
  if (refinement.whole_run) {
    char refined[200];
    std::snprintf(refined, sizeof refined,
                  refinement.kept ? "\nrefined by output error over whole runs: multiple shooting, segments of %g s"
                                  : "\noutput error over whole runs (segments of %g s) tried and not kept: the "
                                    "held-out quarters were simulated no better",
                  refinement.segment);
    comment = refined;
  } else {
    // Any number of lengths (0.1+0.2+...): built, not printed into a fixed buffer.
    const std::string lengths = OutputErrorWindowLengths(refinement.horizon, refinement.also_horizons);
    const std::string at_once = refinement.also_horizons.empty() ? "" : " (fitted at once)";
    comment = refinement.kept ? "\nrefined by output error: windows of " + lengths + " s simulated from the logs' "
                                "torques" + at_once
                              : "\noutput error on windows of " + lengths + " s" + at_once +
                                    " tried and not kept: the held-out windows were simulated no better";
  }
  if (refinement.stribeck_tried) {
    const std::string kind =
        presliding.empty()
            ? "friction that holds at low speed (stribeck_friction)"
            : "friction that deflects before it slides (stribeck_friction with " +
                  std::string(presliding == "lugre" ? "LuGre bristles" : "a Maxwell-slip element") + ")";
    comment += refinement.stribeck_kept ? "\nwith " + kind + ", chosen on the held-out windows"
                                        : "\n" + kind + " tried and not kept: under 10 % better on the held-out windows";
  }
  return comment;
}

// The identified model file's comment: the logs, the starting model and how the estimate
// was refined (each output-error stage in turn).
std::string IdentifiedArmComment(const IdentifyCliOptions& options, std::size_t logs,
                                 const ArmIdentificationReport& found,
                                 double cutoff_hz,  // Hz, 0: nothing derived
                                 const std::string& knots_brief) {  // the auto knots' choices, or empty
  const std::vector<ArmOutputErrorSummary>& refinements = found.output_error;
  std::string comment = "Identified by twinsim identify from " + std::to_string(logs) + " log(s):";
  for (const auto& path : options.logs) comment += "\n  " + path;
  char cutoff[96] = "";
  if (cutoff_hz > 0) {
    std::snprintf(cutoff, sizeof cutoff, "; derivatives at %g Hz%s", cutoff_hz,
                  options.cutoff == "auto" ? " (auto)" : "");
  }
  comment += "\nstarting from " + options.model + cutoff + "; " + found.least_squares.BriefReport();
  if (!knots_brief.empty()) comment += "\n" + knots_brief;
  if (found.started_from_a_priori)
    comment += "\noutput error from the a-priori model's inertia and friction (it simulated the first stage's rows "
               "better than the least squares' estimate)";
  if (refinements.size() > 1) comment += "\noutput error as a continuation, each stage from where the last ended:";
  for (const ArmOutputErrorSummary& refinement : refinements) comment += RefinementComment(refinement, options.presliding);
  return comment;
}

// Writes --report's tables (with output error its fit's values and standard errors) and,
// where rendering is compiled, the first log's torque plot per joint.
void WriteArmIdentifyReport(const std::string& report_dir, const ArmModel& model, const ArmModel& identified,
                            const ArmLog& first_log, const ArmIdentificationReport& found, OutputFiles* files) {
  const std::string report = report_dir + "/";
  files->Write(report + "parameters.csv", FormatIdentifiedParametersCsv(found.least_squares));
  files->Write(report + "joints.csv", FormatIdentifiedJointsCsv(found.least_squares));
  if (!found.validation.logs.empty()) {  // held-out logs were given
    files->Write(report + "validation.csv", FormatIdentificationValidationCsv(found.validation));
    files->Write(report + "simulation.csv", FormatArmSimulationScoresCsv(found.validation.simulated));
  }
  if (!found.output_error.empty()) files->Write(report + "output_error.csv", FormatArmOutputErrorCsv(found.output_error));
  if (RenderingCompiled()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    const Eigen::MatrixXd before = PredictArmCommands(model, first_log);
    const Eigen::MatrixXd after = PredictArmCommands(identified, first_log);
    for (int j = 0; j < model.dof(); ++j) {
      files->WritePng(report + "torque_joint" + std::to_string(j + 1) + ".png",
                      RenderSeriesPlot(TorquePlot(first_log, j, before, after, model.name), *renderer));
    }
  } else {
    std::fprintf(stderr, "identify: warning: plots not drawn: %s\n", kRenderingNotCompiled);
  }
}

int Identify(const IdentifyCliOptions& options) {
  if (ModelFileRobot(options.model) == RobotKind::kOmni) return IdentifyOmniCli(options);
  // Check everything before identifying or writing.
  std::vector<ArmOutputErrorOptions> stages;
  const WlsIdentificationOptions identification = CheckArmIdentifyOptions(options, &stages);
  const ArmModel model = LoadArmModel(options.model);
  double cutoff_hz = 0;
  std::string cutoff_brief;
  std::vector<ArmLog> logs =
      ReadArmLogsAtCutoff(options.logs, options.cutoff, model, identification, &cutoff_hz, &cutoff_brief);
  // The held-out logs derived as the fitted ones were.
  char chosen[32];
  std::snprintf(chosen, sizeof chosen, "%.17g", cutoff_hz);
  std::vector<ArmLog> held_out = ReadArmLogsAtCutoff(options.validate, chosen, model, identification);
  std::string knots_brief;
  WlsIdentificationOptions least_squares = identification;
  // auto: the friction's knots first (without a position torque), then the torque's.
  for (const bool torque : {false, true}) {
    if ((torque ? options.position_torque : options.position_friction) != "auto") continue;
    PositionFrictionChoiceOptions choose;
    choose.identification = least_squares;
    choose.torque = torque;
    const PositionFrictionChoice choice = ChoosePositionFrictionKnots(model, logs, choose);
    (torque ? least_squares.position_torque_knots : least_squares.position_friction_knots) = choice.knots;
    knots_brief += (knots_brief.empty() ? "" : "\n") + choice.Brief();
  }

  ArmIdentificationOptions arm;
  arm.least_squares = least_squares;
  arm.output_error = stages;
  ArmModel identified;
  const ArmIdentificationReport report = IdentifyArm(model, logs, held_out, arm, &identified);

  OutputFiles files;
  files.Write(options.out,
              FormatArmModelYaml(identified, IdentifiedArmComment(options, logs.size(), report,
                                                                  logs.front().derive_cutoff_hz, knots_brief)));
  if (!options.report.empty())
    WriteArmIdentifyReport(options.report, model, identified, logs[0], report, &files);

  if (!options.quiet) {
    std::printf("identified %s (%d joints) from %zu log(s)\n", model.name.c_str(), model.dof(), logs.size());
    if (!cutoff_brief.empty()) std::printf("%s\n", cutoff_brief.c_str());
    if (!knots_brief.empty()) std::printf("%s\n", knots_brief.c_str());
    std::printf("\n%s", report.FullReport().c_str());
    files.PrintWrote();
  }
  return kExitOk;
}

// The options only an arm's identification reads (the least squares, the validation and
// the output-error refinement).
void AddArmIdentifyOptions(CLI::App* cmd, IdentifyCliOptions* options) {
  AddDerivativeCutoffOption(cmd, &options->cutoff);
  cmd->add_option("--decimate", options->identification.decimate, "Use every k-th sample")->capture_default_str();
  cmd->add_option("--max-condition", options->identification.max_condition_number,
                  "Largest condition number of the scaled regressor before parameters count as not excited")
      ->capture_default_str();
  cmd->add_flag("--unweighted", options->unweighted, "Ordinary least squares only (no per-joint weights)");
  cmd->add_flag("--offsets", options->offsets,
                "Also estimate a constant torque offset per joint (a torque sensor's bias), written as torque_offset effects");
  cmd->add_option("--position-friction", options->position_friction,
                  "Also estimate each moving joint's Coulomb friction at this many evenly spaced positions along "
                  "its travel (2 to 12; linear between them), written as position_friction effects; auto: 0, 3, 5 "
                  "or 9, whichever predicts held-out blocks' torques best (fewer within 2 %); 0 = one level")
      ->capture_default_str();
  cmd->add_option("--position-torque", options->position_torque,
                  "Also estimate a torque that varies along each moving joint's travel (a cable, a spring, a tilt), "
                  "at this many evenly spaced positions (2 to 12; linear between them), written as position_torque "
                  "effects; auto: 0, 3, 5 or 9 as for --position-friction; 0 = none")
      ->capture_default_str();
  cmd->add_option("--validate", options->validate,
                  "Held-out log(s): print the a-priori and identified models' torque errors on them and the motion "
                  "they simulate from the logs' torques");
  cmd->add_option("--output-error", options->output_error,
                  "s: refine the estimate by output error, on windows of this length simulated from the logs' "
                  "torques (link inertial scales, friction, offsets); run: on each log's free run, by multiple "
                  "shooting, its last quarter held out; 0.1+1 fits windows of both lengths at once (one model for "
                  "the short horizon and the long, each length weighed alike); a list (0.1,0.5,1) refines stage "
                  "after stage, each from "
                  "where the last ended and kept by its own held-out windows; the first from the least squares' "
                  "estimate, or from the a-priori model (with the estimated offsets) where that simulates its fit "
                  "windows better; 0 = off")
      ->capture_default_str();
  cmd->add_option("--segment", options->segment, "s: with --output-error run, the shooting segments' length")
      ->capture_default_str();
  cmd->add_flag("--stribeck", options->stribeck,
                "With --output-error: also fit a break-away above the Coulomb level per joint (stribeck_friction), "
                "kept only where it simulates the held-out windows at least 10 % better");
  cmd->add_option("--presliding", options->presliding,
                  "With --output-error: --stribeck with the friction acting through bristles that deflect before "
                  "they slide, their stiffness fitted per joint too (stribeck_friction's sigma0; sigma1 damping them "
                  "critically): lugre (bristles that creep under load) or maxwell (a Maxwell-slip element: a damped "
                  "spring that slips at the friction level); kept under the same 10 % rule")
      ->check(CLI::IsMember({"lugre", "maxwell"}));
  cmd->add_option("--report", options->report,
                  "Folder for parameters.csv, joints.csv, output_error.csv (with --output-error) and "
                  "torque_joint<j>.png (measured vs models, first log)");
}

}  // namespace

void AddIdentifyCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<IdentifyCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "identify", "Estimate a robot's parameters from its logs: an arm's inertia and friction, an omni robot's response.");
  cmd->footer(
      "Weighted least squares (seed 001): the torques are linear in the base parameters; OLS first,\n"
      "then each joint weighted by 1 / its residual's standard deviation, solved by QR. Logs are\n"
      "t,q1..qn,tau1..taun with optional qd, qdd (derived from q by zero-phase filtered\n"
      "differentiation where absent). Prints the a-priori and identified parameters with their\n"
      "relative standard deviations and the torque RMS error per joint before and after. The\n"
      "written model (YAML, URDF-style joint table) is physically consistent and loads anywhere a\n"
      "model does. With --offsets the offsets are written as torque_offset effects (tau0 = -offset);\n"
      "with --position-friction each moving joint's Coulomb friction at its knots as the joint's\n"
      "lowest level and a position_friction effect with the rest; with --position-torque a\n"
      "position_torque effect (beside --offsets its first level is 0: the offset holds it).\n"
      "The input model's friction effects, payload and torque offsets are dropped (the identified\n"
      "parameters hold their torques); its time_delay, torque_saturation and joint_flexibility are\n"
      "kept. Data that does not excite a parameter is refused (exit 2) naming it.\n"
      "\n"
      "Omni robots (a model with robot: omni): the total delay, per axis the share of the command\n"
      "reached, the set-point ramp, a lag and the speed limits, and the couplings between axes\n"
      "(a sideways command turning the robot), fitted to the logs' 4-frame predictions on time\n"
      "blocks and scored on held-out blocks beside constant-velocity extrapolation. --out DIR\n"
      "writes DIR/model.yaml, report.json (every parameter with its standard error) and\n"
      "report.html; --out M.yaml writes the model, and the reports into --report DIR if given.\n"
      "Method: docs/identification.md.");
  cmd->add_option("--model", options->model, "A-priori arm model (URDF or YAML)")->required();
  cmd->add_option("--log", options->logs, "Measured arm log(s) (repeat --log)")->required();
  cmd->add_option("--out", options->out, "Identified model to write (.yaml); omni: or a folder for model.yaml and reports")
      ->required();
  AddArmIdentifyOptions(cmd, options.get());
  AddLogSelectorOptions(cmd, &options->select);
  cmd->add_option("--held-out", options->omni.held_out, "Omni: share of each log's time blocks held out from the fit")
      ->capture_default_str();
  cmd->add_option("--block", options->omni.block_seconds,
                  "Omni: s, length of a time block; 0 = a 20th of the longest log, 0.5 to 10 s")
      ->capture_default_str();
  cmd->add_option("--horizon", options->omni.horizon, "Omni: frames predicted ahead in the fit and the scores")
      ->capture_default_str();
  cmd->add_option("--backend", options->omni.backend, "Omni: physics that replays the model (analytic, ode, bullet)")
      ->capture_default_str();
  cmd->add_option("--stride", options->omni.stride, "Omni: the fit predicts from every stride-th frame")
      ->capture_default_str();
  cmd->add_option("--state", options->omni.state,
                  "Omni: each prediction starts from the model's Kalman filter (observer; its driving noise is fitted "
                  "too) or from the open-loop tracker (tracker)")
      ->type_name("TEXT")
      ->transform(EnumWords({std::begin(kOmniReplayStateWords), std::end(kOmniReplayStateWords)}))
      ->default_str(OmniReplayStateName(options->omni.state));
  cmd->add_option("--max-delay", options->omni.max_delay, "Omni: s, the longest total delay searched")->capture_default_str();
  cmd->add_flag("!--no-noise", options->omni.noise,
                "Omni: keep the prediction-error fit's noise; without it the driving noise is identified anew for "
                "predictions ahead and the simulation (likelihood at 4, 16 and 63 frames, some 20-40 s more)");
  cmd->add_flag("!--no-drift", options->omni.drift,
                "Omni: no drift; without it a slow slip beside the driving noise (a run's own drift, which the observer "
                "learns and carries ahead) is fitted on the predictions 0.5 and 1 s ahead and kept where it takes 5 % "
                "off them and the held-out blocks are no worse");
  cmd->add_flag("!--no-turn-harmonics", options->omni.turn_harmonics,
                "Omni, three wheels: no turn by direction; without it, where the fit logs drive in enough directions, a "
                "turn of v (s sin 3φ + c cos 3φ) (turn_coupling's third_sin and third_cos) is fitted and kept where the "
                "held-out blocks' poses a quarter second ahead come 1 % nearer");
  cmd->add_option("--safeguard", options->omni.safeguard,
                  "Omni: the intervals' conformal scale per horizon, fitted on the two halves of the held-out blocks "
                  "(blocks), and with logs a growth on top with the distance of a prediction's inputs from those the "
                  "fit saw, fitted on each log predicted by the model of the others (identification once more per "
                  "log), or none (off); kept only where it helps rows it was not fitted on")
      ->type_name("TEXT")
      ->transform(EnumWords({std::begin(kOmniSafeguardWords), std::end(kOmniSafeguardWords)}))
      ->default_str(kOmniSafeguardWords[static_cast<int>(options->omni.safeguard)]);
  cmd->add_option("--threads", options->omni.threads,
                  "Omni, and an arm's --output-error: worker threads (0: one per core); results do not depend on it")
      ->capture_default_str();
  cmd->add_flag("--quiet,-q", options->quiet, "No tables and no summary");
  cmd->callback([cmd, options, exit_code] {
    for (const CLI::Option* o : cmd->get_options())
      if (o->count() > 0) options->given.push_back(o->get_name());
    *exit_code = Identify(*options);
  });
}

}  // namespace twinsim
