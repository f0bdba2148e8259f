// `twinsim excite --model MODEL --out DIR [--harmonics N] [--fundamental HZ] [--seed N] ...
//  [--trajectory FILE] [--plant PLANT --trials N ...]`
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/commands/commands.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "identification/batch_adaptive.h"
#include "identification/excitation_design.h"
#include "identification/fourier_trajectory.h"
#include "io/output_files.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace {

struct ExciteCliOptions {
  std::string model;
  std::string out;
  std::string trajectory;  // use this excitation instead of designing one
  ExcitationOptions design;
  std::vector<double> acceleration_limits;  // one for all joints, or one per joint
  int periods = 1;
  // Batch-adaptive estimation on a simulated plant.
  std::string plant;
  BatchAdaptiveOptions adaptive;
  double torque_noise = 0;        // N·m, std on every joint
  double encoder_resolution = 0;  // rad or m per count
  bool quiet = false;
};

// Joint positions over one period.
SeriesPlot TrajectoryPlot(const ArmModel& model, const FourierTrajectory& t, const std::string& title) {
  SeriesPlot plot;
  plot.title = title;
  plot.y_label = "q [rad]";
  constexpr int kPoints = 2000;
  for (int i = 0; i < t.dof(); ++i) {
    PlotSeries s{model.joints[static_cast<std::size_t>(i)].name, {}, {}};
    for (int k = 0; k <= kPoints; ++k) {
      const double time = t.period() * k / kPoints;
      s.x.push_back(time);
      s.y.push_back(EvaluateFourier(t, time).q[i]);
    }
    plot.series.push_back(std::move(s));
  }
  return plot;
}

// Seed Fig. 5: each base parameter's estimate per trial relative to its final value
// (trial 0: the initial estimate); parameters causing under 1 % of the largest torque
// contribution are left out (their ratio is dominated by their closeness to zero).
SeriesPlot ParameterPlot(const BatchAdaptiveResult& r, int* left_out) {
  SeriesPlot plot;
  plot.title = "Batch-adaptive estimates per trial, relative to the final ones";
  plot.x_label = "trial";
  plot.y_label = "estimate / final estimate";
  const Eigen::VectorXd contribution = r.scales.cwiseProduct(r.beta).cwiseAbs();
  const double largest = contribution.maxCoeff();
  *left_out = 0;
  for (int c = 0; c < r.beta.size(); ++c) {
    if (contribution[c] < 0.01 * largest) {
      ++*left_out;
      continue;
    }
    PlotSeries s{r.short_names[static_cast<std::size_t>(c)], {0.0}, {r.initial[c] / r.beta[c]}};
    for (const BatchAdaptiveTrial& t : r.trials) {
      s.x.push_back(t.trial);
      s.y.push_back(t.beta_next[c] / r.beta[c]);
    }
    plot.series.push_back(std::move(s));
  }
  return plot;
}

// Tracking error RMS per joint and trial, on a log scale.
SeriesPlot TrackingPlot(const ArmModel& model, const BatchAdaptiveResult& r) {
  SeriesPlot plot;
  plot.title = "Tracking error per trial";
  plot.x_label = "trial";
  plot.y_label = "log10 RMS error [mrad]";
  for (int i = 0; i < model.dof(); ++i) {
    PlotSeries s{model.joints[static_cast<std::size_t>(i)].name, {}, {}};
    for (const BatchAdaptiveTrial& t : r.trials) {
      s.x.push_back(t.trial);
      s.y.push_back(std::log10(std::max(t.error_rms[i] * 1e3, 1e-9)));
    }
    plot.series.push_back(std::move(s));
  }
  return plot;
}

// Checks the options against the model and loads the plant, if given, before anything runs or is written.
std::unique_ptr<ArmModel> CheckExciteOptions(const ArmModel& model, ExciteCliOptions* options,
                                             ArmTrialOptions* plant_options) {
  const int n = model.dof();
  if (!options->acceleration_limits.empty()) {
    if (options->acceleration_limits.size() == 1)
      options->acceleration_limits.assign(static_cast<std::size_t>(n), options->acceleration_limits[0]);
    options->design.acceleration_limits = options->acceleration_limits;
  }
  options->design.threads = ResolveThreadCount(options->design.threads);  // 0: one per core
  std::string invalid;
  if (!options->design.IsValid(&invalid)) {
    // Said by the option's name, where the design's field has one.
    for (const auto& [field, option] : {std::pair<const char*, const char*>{"samples_per_period", "--samples"},
                                        {"max_iterations", "--iterations"},
                                        {"position_margin", "--position-margin"},
                                        {"torque_fraction", "--torque-fraction"},
                                        {"starts", "--starts"},
                                        {"harmonics", "--harmonics"},
                                        {"fundamental", "--fundamental"}}) {
      if (invalid.rfind(field, 0) == 0) invalid = option + invalid.substr(std::string(field).size());
    }
    throw InputError("excite: " + invalid);
  }
  ResolveExcitationLimits(model, options->design);
  std::unique_ptr<ArmModel> plant;
  if (!options->plant.empty()) {
    plant = std::make_unique<ArmModel>(LoadArmModel(options->plant));
    if (plant->dof() != n)
      throw InputError(options->plant + ": the plant has " + std::to_string(plant->dof()) + " joint(s) but model '" +
                       model.name + "' has " + std::to_string(n));
    if (!options->adaptive.IsValid(&invalid)) throw InputError("excite: " + invalid);
    plant_options->encoder_resolution = options->encoder_resolution;
    plant_options->torque_noise = Eigen::VectorXd::Constant(n, options->torque_noise);
    plant_options->seed = options->design.seed;
    if (!plant_options->IsValid(&invalid)) throw InputError("excite: " + invalid);
  }
  return plant;
}

// Designs the excitation with a progress line, or loads --trajectory and checks it fits the model.
FourierTrajectory DesignOrLoadExcitation(const ArmModel& model, const ExciteCliOptions& options,
                                         ExcitationSummary* summary) {
  if (!options.trajectory.empty()) {
    FourierTrajectory trajectory = LoadFourierTrajectory(options.trajectory);
    CheckTrajectoryFitsModel(trajectory, model, options.trajectory);
    return trajectory;
  }
  Progress progress("excite", !options.quiet);
  FourierTrajectory trajectory =
      DesignExcitation(model, options.design, summary, [&](int done, int total, double best) {
        char detail[64];
        std::snprintf(detail, sizeof detail, "start %d/%d, best condition %.4g", done, total, best);
        progress.Update(done, total, detail);
      });
  progress.Finish();
  return trajectory;
}

// Draws excitation.png and, after a batch-adaptive run, its parameter and tracking plots; returns the parameters the
// parameter plot leaves out.
int DrawExcitePlots(const ArmModel& model, const FourierTrajectory& trajectory, const BatchAdaptiveResult* adaptive,
                    OutputFiles* files) {
  int parameters_left_out = 0;
  if (!RenderingCompiled()) {
    std::fprintf(stderr, "excite: warning: plots not drawn: %s\n", kRenderingNotCompiled);
    return parameters_left_out;
  }
  std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
  char title[160];
  std::snprintf(title, sizeof title, "Excitation of %s: %d harmonics of %g Hz", model.name.c_str(),
                trajectory.harmonics(), trajectory.fundamental);
  files->WritePng("excitation.png", RenderSeriesPlot(TrajectoryPlot(model, trajectory, title), *renderer));
  if (adaptive) {
    files->WritePng("adaptive_parameters.png",
                    RenderSeriesPlot(ParameterPlot(*adaptive, &parameters_left_out), *renderer));
    files->WritePng("adaptive_tracking.png", RenderSeriesPlot(TrackingPlot(model, *adaptive), *renderer));
  }
  return parameters_left_out;
}

// Prints the design's summary, or a loaded excitation's condition number, and the batch-adaptive report.
void PrintExciteSummary(const ArmModel& model, const ExciteCliOptions& options, const FourierTrajectory& trajectory,
                        const ExcitationSummary& summary, const BatchAdaptiveResult* adaptive,
                        int parameters_left_out) {
  if (options.trajectory.empty()) {
    std::printf("%s", summary.FullReport().c_str());
  } else {
    const BaseParameters base = FindBaseParameters(model);
    const ExcitationLimits limits = ResolveExcitationLimits(model, options.design);
    const int samples = options.design.samples_per_period;
    std::printf("excitation %s: condition number %.4g (scaled columns, %d samples per period)\n",
                options.trajectory.c_str(),
                ExcitationCondition(model, base, ExcitationColumnScales(model, base, limits), trajectory, samples),
                samples);
  }
  if (adaptive) {
    std::printf("\n%s", adaptive->FullReport().c_str());
    if (parameters_left_out > 0)
      std::printf("(adaptive_parameters.png leaves out %d parameter(s) causing under 1 %% of the largest torque)\n",
                  parameters_left_out);
  }
}

int Excite(ExciteCliOptions options) {
  // Check everything before running or writing anything.
  const ArmModel model = LoadArmModel(options.model);
  ArmTrialOptions plant_options;
  const std::unique_ptr<ArmModel> plant = CheckExciteOptions(model, &options, &plant_options);

  ExcitationSummary summary;
  const FourierTrajectory trajectory = DesignOrLoadExcitation(model, options, &summary);

  OutputFiles files(options.out);
  SaveFourierTrajectory(trajectory, files.Path("excitation.yaml"));
  files.Add("excitation.yaml");
  files.Write("reference.csv", FormatReferenceCsv(model, trajectory, model.sample_time, options.periods));

  std::unique_ptr<BatchAdaptiveResult> adaptive;
  if (plant) {
    Progress progress("batch-adaptive", !options.quiet);
    adaptive = std::make_unique<BatchAdaptiveResult>(RunBatchAdaptive(
        model, trajectory, options.adaptive, SimulatedTrials(*plant, plant_options),
        [&](int trial, int trials, double change) {
          char detail[64];
          std::snprintf(detail, sizeof detail, "trial %d, parameter change %.2e", trial, change);
          progress.Update(trial, trials, detail);
        }));
    progress.Finish();
    files.Write("adaptive.csv", FormatBatchAdaptiveCsv(*adaptive));
  }

  const int parameters_left_out = DrawExcitePlots(model, trajectory, adaptive.get(), &files);
  if (!options.quiet) {
    PrintExciteSummary(model, options, trajectory, summary, adaptive.get(), parameters_left_out);
    files.PrintWrote();
  }
  return kExitOk;
}

}  // namespace

void AddExciteCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<ExciteCliOptions>();
  CLI::App* cmd = app.add_subcommand("excite", "Design an optimised excitation trajectory for an arm; optionally "
                                               "estimate its parameters batch-adaptively on a simulated plant.");
  cmd->footer(
      "The excitation is a finite Fourier series per joint with the coefficients that minimise the condition\n"
      "number of the base regressor stacked over one period (columns scaled to their typical size), within\n"
      "the model's position limits less a margin, its velocity limits, the acceleration limits, and a fraction\n"
      "of its effort limits for the nominal torque; it starts and ends at rest. Outputs in DIR:\n"
      "  excitation.yaml   the trajectory (fundamental_hz, per joint q0, a, b; docs/excitation.md)\n"
      "  reference.csv     t,q1..qn,qd1..qdn,qdd1..qddn,qref1..qrefn,tau1..taun at the model's sample time\n"
      "                    (an arm log; tau is the model's inverse dynamics along the reference)\n"
      "  excitation.png    the joint positions over one period\n"
      "With --plant (a model file standing for the real arm), the arm tracks the excitation trial after trial\n"
      "under PD feedback plus the model's feedforward, and the parameters are updated from each trial's\n"
      "feedback effort (batch-adaptive estimation, seed 001 section IV-A); the estimator never reads the plant.\n"
      "  adaptive.csv              trial,<base parameters>,rms1..n,max1..n,fb_rms1..n,change\n"
      "  adaptive_parameters.png   the estimates per trial relative to the final ones (seed Fig. 5)\n"
      "  adaptive_tracking.png     the tracking error per trial");
  cmd->add_option("--model", options->model, "Arm model (URDF or YAML)")->required();
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->add_option("--harmonics", options->design.harmonics, "N, harmonics per joint")->capture_default_str();
  cmd->add_option("--fundamental", options->design.fundamental, "Fundamental frequency [Hz]; the period is 1/f")
      ->capture_default_str()
      ->check(PositiveNumber());
  cmd->add_option("--seed", options->design.seed, "Seed of the random starts (and of the plant's noise)")
      ->capture_default_str();
  cmd->add_option("--starts", options->design.starts, "Random feasible starting points")->capture_default_str();
  cmd->add_option("--iterations", options->design.max_iterations, "LBFGS iterations per penalty round")
      ->capture_default_str();
  cmd->add_option("--samples", options->design.samples_per_period, "Regressor samples per period in the criterion")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--threads", options->design.threads,
                  "Threads for the starts, 0: one per core (the result does not depend on it)")
      ->capture_default_str()
      ->check(NonNegativeNumber());
  cmd->add_option("--acceleration-limit", options->acceleration_limits,
                  "Acceleration limit [rad/s^2]: one for all joints or one per joint (default 20)")
      ->expected(1, 64);
  cmd->add_option("--position-margin", options->design.position_margin,
                  "Kept from each position limit [rad]")->capture_default_str();
  cmd->add_option("--torque-fraction", options->design.torque_fraction,
                  "Nominal torque within this fraction of each effort limit (0: not constrained)")
      ->capture_default_str();
  cmd->add_option("--periods", options->periods, "Periods written to reference.csv")
      ->capture_default_str()
      ->check(PositiveNumber())
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--trajectory", options->trajectory, "Use this excitation.yaml instead of designing one")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plant", options->plant, "Run batch-adaptive estimation on this model as the simulated arm");
  cmd->add_option("--trials", options->adaptive.max_trials, "Most trials")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--tolerance", options->adaptive.tolerance, "Relative parameter change that ends the trials")
      ->capture_default_str()
      ->check(PositiveNumber());
  cmd->add_option("--bandwidth", options->adaptive.feedback_bandwidth, "PD feedback bandwidth [Hz]")
      ->capture_default_str()
      ->check(PositiveNumber());
  cmd->add_option("--torque-noise", options->torque_noise, "Plant: torque noise std on every joint [N m]")
      ->capture_default_str()
      ->check(NonNegativeNumber());
  cmd->add_option("--encoder-resolution", options->encoder_resolution, "Plant: encoder resolution [rad]; 0: exact")
      ->capture_default_str()
      ->check(NonNegativeNumber());
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] { *exit_code = Excite(*options); });
}

}  // namespace twinsim
