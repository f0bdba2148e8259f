// `twinsim identify --model MODEL --log LOG.csv [--log ...] --out MODEL_OUT`
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands/commands.h"
#include "app/progress.h"
#include "core/error.h"
#include "identification/torque_prediction.h"
#include "identification/wls_identification.h"
#include "io/arm_log.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/png_image.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_yaml_writer.h"

namespace twinsim {
namespace {

struct IdentifyCliOptions {
  std::string model;
  std::vector<std::string> logs;
  std::vector<std::string> validate;
  std::string out;
  std::string report;
  ArmLogOptions log;
  WlsIdentificationOptions identification;
  bool unweighted = false;
  bool offsets = false;
  bool quiet = false;
};

std::string NoCommas(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  return s;
}

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

int Identify(const IdentifyCliOptions& options) {
  // Check everything before identifying or writing.
  std::string ext = std::filesystem::path(options.out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".yaml" && ext != ".yml")
    throw InputError("--out " + options.out + ": the identified model is written as YAML; give a .yaml or .yml path");
  if (ModelFileRobotKind(options.model) != "arm")
    throw InputError(SourceLocation{options.model}, "identify estimates an arm's parameters; this is not an arm model");
  WlsIdentificationOptions identification = options.identification;
  identification.weighted = !options.unweighted;
  identification.torque_offsets = options.offsets;
  std::string why;
  if (!identification.IsValid(&why)) throw InputError(why);
  const ArmModel model = LoadArmModel(options.model);
  std::vector<ArmLog> logs;
  for (const auto& path : options.logs) {
    logs.push_back(ReadArmLog(path, options.log));
    CheckArmLogMatchesModel(logs.back(), model);
  }

  std::vector<ArmLog> held_out;
  for (const auto& path : options.validate) {
    held_out.push_back(ReadArmLog(path, options.log));
    CheckArmLogMatchesModel(held_out.back(), model);
  }

  WlsIdentificationSummary summary;
  const ArmModel identified = IdentifyArm(model, logs, identification, &summary);

  // Held-out logs: the a-priori and the identified model's torque errors (with the
  // identified offsets, when estimated), away from the derived derivatives' edges.
  // The unconstrained estimate predicts from the base parameters directly.
  std::string validation_csv =
      "log,joint,torque_rms,error_a_priori,error_identified,error_unconstrained,relative_a_priori,"
      "relative_identified,relative_unconstrained\n";
  std::string validation_text;
  const BaseParameters base = held_out.empty() ? BaseParameters{} : IdentificationBase(model, identification);
  for (const ArmLog& log : held_out) {
    // The identified model's commands: its offsets (torque_offset effects) and the
    // a-priori model's delays and other kept effects included, as replay gives them.
    const Eigen::MatrixXd tau = PredictArmCommands(identified, log);
    Eigen::MatrixXd free = PredictBaseTorques(model, base, summary.identified.head(summary.base_parameters), log);
    if (summary.offsets.size() == log.dof) free.rowwise() += summary.identified.tail(log.dof).transpose();
    const int first = log.edge_samples, last = log.rows() - log.edge_samples;
    const TorqueErrors before = CompareArmTorques(model, log, first, last);
    const TorqueErrors after = CompareArmTorques(identified, log, tau, first, last);
    const TorqueErrors unconstrained = CompareArmTorques(identified, log, free, first, last);
    char line[256];
    validation_text += "\nheld out: " + log.path + " (" + std::to_string(after.rows) + " rows)\n";
    std::snprintf(line, sizeof line, "%-6s %11s %21s %21s %21s\n", "joint", "torque RMS", "a-priori error",
                  "identified error", "(unconstrained)");
    validation_text += line;
    for (int j = 0; j < log.dof; ++j) {
      std::snprintf(line, sizeof line, "%-6d %11.4g %11.4g (%6.2f%%) %11.4g (%6.2f%%) %11.4g (%6.2f%%)\n", j + 1,
                    after.torque_rms[j], before.error_rms[j], 100 * before.relative[j], after.error_rms[j],
                    100 * after.relative[j], unconstrained.error_rms[j], 100 * unconstrained.relative[j]);
      validation_text += line;
      validation_csv += log.path + "," + std::to_string(j + 1) + "," + FormatCsvNumber(after.torque_rms[j]) + "," +
                        FormatCsvNumber(before.error_rms[j]) + "," + FormatCsvNumber(after.error_rms[j]) + "," +
                        FormatCsvNumber(unconstrained.error_rms[j]) + "," + FormatCsvNumber(before.relative[j]) + "," +
                        FormatCsvNumber(after.relative[j]) + "," + FormatCsvNumber(unconstrained.relative[j]) + "\n";
    }
    std::snprintf(line, sizeof line,
                  "mean relative error %.2f%% -> %.2f%% (unconstrained %.2f%%); normalised (error / twice the effort "
                  "limit) %.3f%% -> %.3f%% (%.3f%%)\n",
                  100 * before.relative.mean(), 100 * after.relative.mean(), 100 * unconstrained.relative.mean(),
                  100 * before.normalised, 100 * after.normalised, 100 * unconstrained.normalised);
    validation_text += line;
  }

  std::string comment = "Identified by twinsim identify from " + std::to_string(logs.size()) + " log(s):";
  for (const auto& path : options.logs) comment += "\n  " + path;
  comment += "\nstarting from " + options.model + "; " + summary.BriefReport();
  WriteArmModelYaml(options.out, identified, comment);
  std::vector<std::string> written = {options.out};

  if (!options.report.empty()) {
    std::string csv = "index,parameter,description,a_priori,identified,relative_std_pct,model\n";
    for (std::size_t k = 0; k < summary.names.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      csv += std::to_string(k + 1) + "," + NoCommas(summary.names[k]) + "," + NoCommas(summary.descriptions[k]) + "," +
             FormatCsvNumber(summary.a_priori[i]) + "," + FormatCsvNumber(summary.identified[i]) + "," +
             (std::isfinite(summary.relative_std[i]) ? FormatCsvNumber(summary.relative_std[i]) : "inf") + "," +
             FormatCsvNumber(summary.consistent[i]) + "\n";
    }
    const std::string parameters = options.report + "/parameters.csv";
    WriteFileAtomically(parameters, csv);
    written.push_back(parameters);
    std::string joints = "joint,torque_rms,error_rms_a_priori,error_rms_identified,error_rms_model,offset\n";
    for (int j = 0; j < summary.dof; ++j) {
      joints += std::to_string(j + 1) + "," + FormatCsvNumber(summary.torque_rms[j]) + "," +
                FormatCsvNumber(summary.error_rms_a_priori[j]) + "," + FormatCsvNumber(summary.error_rms_identified[j]) +
                "," + FormatCsvNumber(summary.error_rms_model[j]) + "," +
                FormatCsvNumber(summary.offsets.size() ? summary.offsets[j] : 0.0) + "\n";
    }
    const std::string joints_path = options.report + "/joints.csv";
    WriteFileAtomically(joints_path, joints);
    written.push_back(joints_path);
    if (!held_out.empty()) {
      const std::string validation_path = options.report + "/validation.csv";
      WriteFileAtomically(validation_path, validation_csv);
      written.push_back(validation_path);
    }
    if (RenderingCompiled()) {
      std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
      const Eigen::MatrixXd before = PredictArmCommands(model, logs[0]);
      const Eigen::MatrixXd after = PredictArmCommands(identified, logs[0]);
      for (int j = 0; j < model.dof(); ++j) {
        const std::string png = options.report + "/torque_joint" + std::to_string(j + 1) + ".png";
        WritePng(png, RenderSeriesPlot(TorquePlot(logs[0], j, before, after, model.name), *renderer));
        written.push_back(png);
      }
    } else {
      std::fprintf(stderr, "identify: warning: plots not drawn: %s\n", kRenderingNotCompiled);
    }
  }

  if (!options.quiet) {
    std::printf("identified %s (%d joints) from %zu log(s)\n\n%s", model.name.c_str(), model.dof(), logs.size(),
                summary.FullReport().c_str());
    if (summary.offsets.size() > 0) {
      std::printf("torque offsets (measured - model), written as torque_offset effects with tau0 = -offset:");
      for (Eigen::Index j = 0; j < summary.offsets.size(); ++j) std::printf(" %.4g", summary.offsets[j]);
      std::printf(" N·m or N\n");
    }
    std::printf("%s\n", validation_text.c_str());
    std::printf("wrote:\n");
    for (const auto& w : written) std::printf("  %s\n", w.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddIdentifyCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<IdentifyCliOptions>();
  CLI::App* cmd = app.add_subcommand("identify", "Estimate an arm's base inertial parameters and friction from logs.");
  cmd->footer(
      "Weighted least squares (seed 001): the torques are linear in the base parameters; OLS first,\n"
      "then each joint weighted by 1 / its residual's standard deviation, solved by QR. Logs are\n"
      "t,q1..qn,tau1..taun with optional qd, qdd (derived from q by zero-phase filtered\n"
      "differentiation where absent). Prints the a-priori and identified parameters with their\n"
      "relative standard deviations and the torque RMS error per joint before and after. The\n"
      "written model (YAML, URDF-style joint table) is physically consistent and loads anywhere a\n"
      "model does. With --offsets the offsets are written as torque_offset effects (tau0 = -offset).\n"
      "The input model's friction effects, payload and torque offsets are dropped (the identified\n"
      "parameters hold their torques); its time_delay, torque_saturation and joint_flexibility are\n"
      "kept. Data that does not excite a parameter is refused (exit 2) naming it.");
  cmd->add_option("--model", options->model, "A-priori arm model (URDF or YAML)")->required();
  cmd->add_option("--log", options->logs, "Measured arm log(s) (repeat --log)")->required();
  cmd->add_option("--out", options->out, "Identified model to write (.yaml)")->required();
  cmd->add_option("--cutoff", options->log.cutoff_hz,
                  "Hz, low-pass cut-off for qd/qdd derived from q (well above the motion's bandwidth)")
      ->capture_default_str();
  cmd->add_option("--decimate", options->identification.decimate, "Use every k-th sample")->capture_default_str();
  cmd->add_option("--max-condition", options->identification.max_condition_number,
                  "Largest condition number of the scaled regressor before parameters count as not excited")
      ->capture_default_str();
  cmd->add_flag("--unweighted", options->unweighted, "Ordinary least squares only (no per-joint weights)");
  cmd->add_flag("--offsets", options->offsets,
                "Also estimate a constant torque offset per joint (a torque sensor's bias), written as torque_offset effects");
  cmd->add_option("--validate", options->validate,
                  "Held-out log(s): print the a-priori and identified models' torque errors on them");
  cmd->add_option("--report", options->report,
                  "Folder for parameters.csv, joints.csv and torque_joint<j>.png (measured vs models, first log)");
  cmd->add_flag("--quiet,-q", options->quiet, "No tables and no summary");
  cmd->callback([options, exit_code] { *exit_code = Identify(*options); });
}

}  // namespace twinsim
