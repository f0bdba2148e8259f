// `twinsim ilc SCENE.yaml --out DIR [--backend B] [--trials N] [--quiet]`: iterative
// learning control of an arm scene (docs/ilc.md): measure the closed-loop process
// sensitivity at several postures, build a learning filter per joint (fitted to it, or
// the controller's model), and run the task trial after trial, learning a feedforward
// between trials.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "app/commands/commands.h"
#include "app/progress.h"
#include "control/iterative_learning.h"
#include "control/tracking_plots.h"
#include "core/error.h"
#include "identification/closed_loop_frf.h"
#include "io/atomic_file.h"
#include "io/base64.h"
#include "io/html_text.h"
#include "io/csv_table.h"
#include "io/png_image.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "scene/arm_scene.h"
#include "signal/butterworth.h"

namespace twinsim {
namespace {

struct IlcCommandOptions {
  std::string scene;
  std::string out;       // empty: out/<scene name>_ilc
  std::string backend;   // empty: the scene's
  int trials = -1;       // -1: the scene's
  bool quiet = false;
};

std::string Num(double v) { return FormatCsvNumber(v); }

// trial,rms1..rmsn,max1..maxn (the contract's columns).
std::string TrialsCsv(const IlcResult& r) {
  const Eigen::Index n = r.error_rms.front().size();
  std::string out = "trial";
  for (Eigen::Index j = 1; j <= n; ++j) out += ",rms" + std::to_string(j);
  for (Eigen::Index j = 1; j <= n; ++j) out += ",max" + std::to_string(j);
  out += '\n';
  for (std::size_t k = 0; k < r.error_rms.size(); ++k) {
    out += std::to_string(k);
    for (Eigen::Index j = 0; j < n; ++j) out += ',' + Num(r.error_rms[k][j]);
    for (Eigen::Index j = 0; j < n; ++j) out += ',' + Num(r.error_max[k][j]);
    out += '\n';
  }
  return out;
}

// joint,posture,frequency,magnitude,phase,filter_magnitude,filter_phase: the measured
// PS (rad/(N·m), degrees) and 1/L of the learning filter used.
std::string FrfCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters) {
  std::string out = "joint,posture,frequency,magnitude,phase,filter_magnitude,filter_phase\n";
  for (std::size_t j = 0; j < frf.response.size(); ++j) {
    for (std::size_t p = 0; p < frf.response[j].size(); ++p) {
      for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
        const std::complex<double> ps = frf.response[j][p][i];
        const std::complex<double> inv = 1.0 / filters[j].Response(frf.frequency[i], frf.sample_time);
        out += std::to_string(j + 1) + ',' + std::to_string(p + 1) + ',' + Num(frf.frequency[i]) + ',' +
               Num(std::abs(ps)) + ',' + Num(std::arg(ps) * 180 / M_PI) + ',' + Num(std::abs(inv)) + ',' +
               Num(std::arg(inv) * 180 / M_PI) + '\n';
      }
    }
  }
  return out;
}

// joint,shift,inertia,inertia_early,damping,stiffness,residual,limit_hz,q_order,q_cutoff,worst_factor
std::string FiltersCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters, const IlcOptions& o) {
  std::string out =
      "joint,shift,inertia,inertia_early,damping,stiffness,residual,learning_limit_hz,q_order,q_cutoff,worst_factor\n";
  for (std::size_t j = 0; j < filters.size(); ++j) {
    const LearningFilter& l = filters[j];
    const double limit = LearningLimitFrequency(frf, static_cast<int>(j), l, o.gain);
    out += std::to_string(j + 1) + ',' + std::to_string(l.shift) + ',' + Num(l.inertia) + ',' + Num(l.inertia_early) +
           ',' + Num(l.damping) + ',' + Num(l.stiffness) + ',' + Num(l.residual) + ',' +
           (std::isfinite(limit) ? Num(limit) : std::string("inf")) + ',' + std::to_string(o.q_order) + ',' +
           Num(o.q_cutoff) + ',' + Num(ConvergenceFactor(frf, static_cast<int>(j), l, o).maxCoeff()) + '\n';
  }
  return out;
}

// Two images one above the other (the wider sets the width; white around the narrower).
RgbaImage Stack(const RgbaImage& top, const RgbaImage& bottom) {
  RgbaImage out(std::max(top.width, bottom.width), top.height + bottom.height);
  for (int y = 0; y < top.height; ++y)
    for (int x = 0; x < top.width; ++x) std::copy_n(top.at(x, y), 4, out.at(x, y));
  for (int y = 0; y < bottom.height; ++y)
    for (int x = 0; x < bottom.width; ++x) std::copy_n(bottom.at(x, y), 4, out.at(x, top.height + y));
  return out;
}

// log10 of the RMS error per joint and the worst joint over the trials.
SeriesPlot ConvergencePlot(const IlcResult& r, const std::string& title) {
  SeriesPlot plot;
  plot.title = title;
  plot.x_label = "trial";
  plot.y_label = "log10(RMS error / rad)";
  const Eigen::Index n = r.error_rms.front().size();
  for (Eigen::Index j = 0; j <= n; ++j) {
    PlotSeries s;
    s.name = j < n ? "joint " + std::to_string(j + 1) : "worst joint";
    for (std::size_t k = 0; k < r.error_rms.size(); ++k) {
      s.x.push_back(static_cast<double>(k));
      s.y.push_back(std::log10(j < n ? r.error_rms[k][j] : r.WorstRms(static_cast<int>(k))));
    }
    plot.series.push_back(s);
  }
  return plot;
}

// The tracking error of every joint in trial 0 and in the last trial, mrad.
SeriesPlot ErrorPlot(const IlcResult& r, const std::string& title) {
  SeriesPlot plot;
  plot.title = title;
  plot.y_label = "q_ref - q [mrad]";
  const int last = static_cast<int>(r.error_rms.size()) - 1;
  for (const TrackingTrial* trial : {&r.first, &r.last}) {
    for (Eigen::Index j = 0; j < trial->q.cols(); ++j) {
      PlotSeries s;
      s.name = "joint " + std::to_string(j + 1) + ", trial " + std::to_string(trial == &r.first ? 0 : last);
      for (Eigen::Index k = 0; k < trial->q.rows(); ++k) {
        s.x.push_back(trial->t[k]);
        s.y.push_back(1e3 * (trial->q_ref(k, j) - trial->q(k, j)));
      }
      plot.series.push_back(s);
    }
  }
  return plot;
}

// Bode plot of joint j: |PS| in dB and its phase against log10 f, one line per posture,
// and 1/L of the learning filter dashed.
RgbaImage BodePng(const ClosedLoopFrf& frf, const LearningFilter& filter, int j, const std::string& title,
                  Renderer& renderer) {
  SeriesPlot mag, phase;
  mag.title = title;
  mag.x_label = phase.x_label = "log10(f / Hz)";
  mag.y_label = "|PS| [dB re 1 rad/(N m)]";
  phase.y_label = "phase [deg]";
  mag.height = phase.height = 450;
  const auto& responses = frf.response[static_cast<std::size_t>(j)];
  for (std::size_t p = 0; p <= responses.size(); ++p) {
    PlotSeries m, ph;
    m.name = ph.name = p < responses.size() ? "posture " + std::to_string(p + 1) : "1 / L (learning filter)";
    double unwrap = 0, previous = 0;
    for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
      const std::complex<double> v =
          p < responses.size() ? responses[p][i] : 1.0 / filter.Response(frf.frequency[i], frf.sample_time);
      double a = std::arg(v) * 180 / M_PI;
      if (i > 0) {
        while (a + unwrap - previous > 180) unwrap -= 360;
        while (a + unwrap - previous < -180) unwrap += 360;
      }
      previous = a + unwrap;
      m.x.push_back(std::log10(frf.frequency[i]));
      ph.x.push_back(std::log10(frf.frequency[i]));
      m.y.push_back(20 * std::log10(std::abs(v)));
      ph.y.push_back(previous);
    }
    mag.series.push_back(m);
    phase.series.push_back(ph);
  }
  return Stack(RenderSeriesPlot(mag, renderer), RenderSeriesPlot(phase, renderer));
}

int RunIlcCommand(const IlcCommandOptions& options) {
  ArmScene scene = LoadArmScene(options.scene);
  if (options.trials >= 0) scene.ilc.options.trials = options.trials;
  const std::string backend = options.backend.empty() ? scene.backend : options.backend;
  if (backend == "learned") {
    throw InputError(SourceLocation{options.scene}, "twinsim ilc runs on analytic, ode or bullet; the learned backend "
                                                    "needs a predictor per trial and is not supported here");
  }
  const std::string out = options.out.empty() ? "out/" + scene.name + "_ilc" : options.out;
  const ArmReference reference = ArmSceneReference(scene);
  TrackingOptions tracking = scene.tracking;
  tracking.backend = backend;
  tracking.dither = 0;  // learning needs the trials to repeat
  const IlcSpec& spec = scene.ilc;
  const int n = scene.plant.dof();
  const auto start = std::chrono::steady_clock::now();

  // 1. The process sensitivity at the postures.
  const std::vector<Eigen::VectorXd> postures = IlcPostures(scene, reference);
  ClosedLoopFrf frf;
  {
    Progress progress("ilc " + scene.name + ": frequency responses", !options.quiet);
    frf = MeasureProcessSensitivity(scene.plant, scene.hat, postures, tracking, spec.frf, [&](int done, int total) {
      progress.Update(done, total, std::to_string(done) + "/" + std::to_string(total) + " joint-postures");
    });
    progress.Finish();
  }
  const double frf_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // 2. The learning filters.
  std::vector<LearningFilter> filters;
  Eigen::VectorXd mean_posture = Eigen::VectorXd::Zero(n);
  for (const Eigen::VectorXd& p : postures) mean_posture += p / static_cast<double>(postures.size());
  for (int j = 0; j < n; ++j) {
    if (spec.learning_filter == "model") {
      filters.push_back(ModelLearningFilter(scene.hat, tracking, mean_posture, reference.q.row(0).transpose(), j));
    } else {
      try {
        filters.push_back(FitLearningFilter(frf, j, spec.fit_min, spec.fit_max, spec.max_shift));
      } catch (const std::invalid_argument& e) {
        throw InputError(SourceLocation{options.scene}, std::string("ilc.frf.fit_band: ") + e.what());
      }
    }
  }
  if (!options.quiet) {
    std::printf("ilc %s: %d postures, PS measured %g..%g Hz in %.2f s; learning filter %s, gain %g, Q %s\n",
                scene.name.c_str(), static_cast<int>(postures.size()), frf.frequency[0],
                frf.frequency[frf.frequency.size() - 1], frf_seconds, spec.learning_filter.c_str(), spec.options.gain,
                spec.options.q_order > 0 ? ("order " + std::to_string(spec.options.q_order) + " at " +
                                            Num(spec.options.q_cutoff) + " Hz (zero phase)")
                                               .c_str()
                                         : "none");
    for (int j = 0; j < n; ++j) {
      const double limit = LearningLimitFrequency(frf, j, filters[j], spec.options.gain);
      std::printf("  joint %d: %s; |1 - gain PS L| < 1 up to %s; worst |Q|^2 |1 - gain PS L| %.3g\n", j + 1,
                  filters[j].Summary().c_str(), std::isfinite(limit) ? (Num(limit) + " Hz").c_str() : "every line",
                  ConvergenceFactor(frf, j, filters[j], spec.options).maxCoeff());
    }
  }

  // 3. The trials.
  const IlcResult result =
      RunIlc(scene.plant, scene.hat, reference, tracking, filters, spec.options, [&](int trial, const TrackingTrial& t) {
        if (options.quiet) return;
        std::printf("  trial %2d: RMS error [mrad]", trial);
        for (Eigen::Index j = 0; j < t.error_rms.size(); ++j) std::printf(" %9.4g", 1e3 * t.error_rms[j]);
        std::printf("   max [mrad]");
        for (Eigen::Index j = 0; j < t.error_max.size(); ++j) std::printf(" %9.4g", 1e3 * t.error_max[j]);
        std::printf("\n");
        std::fflush(stdout);
      });

  // 4. What it wrote.
  std::vector<std::string> written;
  auto write = [&](const std::string& name, const std::string& text) {
    WriteFileAtomically(out + "/" + name, text);
    written.push_back(out + "/" + name);
  };
  write("trials.csv", TrialsCsv(result));
  write("frf.csv", FrfCsv(frf, filters));
  write("filters.csv", FiltersCsv(frf, filters, spec.options));
  write("feedforward.csv", JointColumnsCsv(reference.t, {"f"}, {&result.feedforward}));

  std::vector<std::pair<std::string, std::string>> images;  // file, PNG bytes
  if (!RenderingCompiled()) {
    std::fprintf(stderr, "%s: warning: plots and report not drawn: %s\n", options.scene.c_str(), kRenderingNotCompiled);
  } else {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    const std::string what = scene.name + " (" + backend + ")";
    images.emplace_back("convergence.png",
                        EncodePng(RenderSeriesPlot(ConvergencePlot(result, what + ": tracking error per trial"), *renderer)));
    images.emplace_back("error.png", EncodePng(RenderSeriesPlot(
                                         ErrorPlot(result, what + ": tracking error, first and last trial"), *renderer)));
    for (int j = 0; j < n; ++j) {
      images.emplace_back("bode_joint" + std::to_string(j + 1) + ".png",
                          EncodePng(BodePng(frf, filters[j], j,
                                            what + ": process sensitivity, joint " + std::to_string(j + 1), *renderer)));
    }
    PathPlot path = ToolPathPlot(result.first, scene.plant, scene.task.writing.tool, what + ": tool path");
    path.paths[1].name = "trial 0";
    PathPlot last = ToolPathPlot(result.last, scene.plant, scene.task.writing.tool, "");
    last.paths[1].name = "trial " + std::to_string(result.error_rms.size() - 1);
    path.paths.push_back(last.paths[1]);
    images.emplace_back("path.png", EncodePng(RenderPathPlot(path, *renderer)));
    for (const auto& [file, png] : images) write(file, png);
  }

  // The report: the story from the FRFs through the filters to the convergence.
  {
    std::ostringstream html;
    const int last = static_cast<int>(result.error_rms.size()) - 1;
    html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>ILC: " << HtmlEscape(scene.name)
         << "</title>\n<style>body{font-family:sans-serif;max-width:1250px;margin:auto}"
            "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
            "img{max-width:100%}</style></head><body>\n";
    html << "<h1>Iterative learning control: " << HtmlEscape(scene.name) << "</h1>\n";
    html << "<p>Plant <b>" << HtmlEscape(scene.plant.name) << "</b>, controller " << HtmlEscape(TrackingControllerName(tracking.controller))
         << " with model <b>" << HtmlEscape(scene.hat.name) << "</b> at " << tracking.bandwidth << " Hz, backend "
         << HtmlEscape(backend) << ". " << last << " learning trials after trial 0 (no learning): the worst joint's RMS error went from "
         << Num(result.WorstRms(0)) << " rad to " << Num(result.WorstRms(last)) << " rad, <b>" << Num(result.Reduction())
         << " times smaller</b>" << (result.Diverged() ? " &mdash; <b>the learning diverged</b>" : "") << ". "
         << "All trials took " << Num(result.wall_seconds) << " s.</p>\n";
    html << "<h2>1. Process sensitivity</h2>\n<p>PS = q / f, from a feedforward torque added to the controller's output to "
            "the joint position with the feedback closed, measured per joint at "
         << postures.size() << " postures by a random-phase multisine (" << Num(spec.frf.f_min) << "&ndash;"
         << Num(spec.frf.f_max) << " Hz, " << spec.frf.periods << " periods of " << Num(spec.frf.period)
         << " s averaged after one transient period).</p>\n";
    for (int j = 0; j < n && !images.empty(); ++j) {
      html << "<img src=\"data:image/png;base64," << Base64Encode(images[2 + j].second) << "\" alt=\"Bode plot joint "
           << j + 1 << "\">\n";
    }
    html << "<h2>2. Filters</h2>\n<p>Learning filter L (" << HtmlEscape(spec.learning_filter)
         << "): L(z) = (a2 z^&tau; + a2' z^(&tau;+1)) (z &minus; 2 + 1/z)/Ts&sup2; + a1 (z &minus; 1/z)/(2Ts) + a0, applied "
            "offline (non-causal). Robustness filter Q: "
         << (spec.options.q_order > 0 ? "zero-phase Butterworth, order " + std::to_string(spec.options.q_order) + ", cut-off " +
                                            Num(spec.options.q_cutoff) + " Hz"
                                      : std::string("none"))
         << ". Update f<sub>k+1</sub> = Q(f<sub>k</sub> + " << Num(spec.options.gain) << " L e<sub>k</sub>).</p>\n<table><tr><th>joint</th><th>&tau; [samples]</th><th>a2 + a2' [kg m&sup2;]</th>"
            "<th>a1 [N m s/rad]</th><th>a0 [N m/rad]</th><th>fit residual</th><th>|1 &minus; &alpha; PS L| &lt; 1 up to [Hz]</th>"
            "<th>worst |Q|&sup2;|1 &minus; &alpha; PS L|</th></tr>\n";
    for (int j = 0; j < n; ++j) {
      const double limit = LearningLimitFrequency(frf, j, filters[j], spec.options.gain);
      html << "<tr><td>" << j + 1 << "</td><td>" << filters[j].shift << "</td><td>"
           << Num(filters[j].inertia + filters[j].inertia_early) << "</td><td>" << Num(filters[j].damping) << "</td><td>"
           << Num(filters[j].stiffness) << "</td><td>" << Num(filters[j].residual) << "</td><td>"
           << (std::isfinite(limit) ? Num(limit) : std::string("all")) << "</td><td>"
           << Num(ConvergenceFactor(frf, j, filters[j], spec.options).maxCoeff()) << "</td></tr>\n";
    }
    html << "</table>\n<h2>3. Convergence</h2>\n<table><tr><th>trial</th>";
    for (int j = 1; j <= n; ++j) html << "<th>RMS " << j << " [mrad]</th>";
    for (int j = 1; j <= n; ++j) html << "<th>max " << j << " [mrad]</th>";
    html << "</tr>\n";
    for (int k = 0; k <= last; ++k) {
      html << "<tr><td>" << k << "</td>";
      for (int j = 0; j < n; ++j) html << "<td>" << Num(1e3 * result.error_rms[k][j]) << "</td>";
      for (int j = 0; j < n; ++j) html << "<td>" << Num(1e3 * result.error_max[k][j]) << "</td>";
      html << "</tr>\n";
    }
    html << "</table>\n";
    for (const auto& [file, png] : images) {
      if (file.rfind("bode", 0) == 0) continue;
      html << "<p><img src=\"data:image/png;base64," << Base64Encode(png) << "\" alt=\"" << file << "\"></p>\n";
    }
    html << "</body></html>\n";
    write("report.html", html.str());
  }

  const int last = static_cast<int>(result.error_rms.size()) - 1;
  if (!options.quiet) {
    std::printf("%s\n", result.Brief().c_str());
    std::printf("wrote:\n");
    for (const auto& w : written) std::printf("  %s\n", w.c_str());
  }
  if (result.Diverged()) {
    std::fprintf(stderr,
                 "%s: ILC diverged: the worst joint's RMS error grew from %g rad (trial 0) to %g rad (trial %d); "
                 "lower the gain or the robustness filter's cut-off (q_cutoff)\n",
                 options.scene.c_str(), result.WorstRms(0), result.WorstRms(last), last);
    return kExitCheckFailed;
  }
  return kExitOk;
}

}  // namespace

void AddIlcCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<IlcCommandOptions>();
  CLI::App* cmd = app.add_subcommand("ilc", "Iterative learning control of an arm scene's task.");
  cmd->footer(
      "Measures the closed-loop process sensitivity PS (feedforward torque to joint position,\n"
      "feedback closed) per joint at several postures with multisines, builds a learning\n"
      "filter L ~ PS^-1 per joint (fitted to the measurement, or the controller's model) and a\n"
      "zero-phase Butterworth robustness filter Q, then runs the scene's task trial after trial\n"
      "from the same initial state, learning f_{k+1} = Q(f_k + gain L e_k) between trials\n"
      "(the scene's `ilc:` block, docs/ilc.md). Trial 0 runs without learning.\n"
      "Writes DIR/trials.csv (trial,rms1..rmsn,max1..maxn: tracking error per joint, rad or m),\n"
      "DIR/frf.csv, DIR/filters.csv, DIR/feedforward.csv, the plots (convergence.png,\n"
      "error.png, bode_joint<j>.png, path.png) and DIR/report.html (self-contained).\n"
      "Exit 1 when the learning diverged (the last trial's worst RMS error is above trial 0's).");
  cmd->add_option("scene", options->scene, "Arm scene file (YAML, docs/scenes.md)")->required();
  cmd->add_option("--out", options->out, "Output folder (default: out/<scene name>_ilc)");
  cmd->add_option("--backend", options->backend, "Backend: analytic, ode or bullet (default: the scene's)");
  cmd->add_option("--trials", options->trials, "Learning trials after trial 0 (default: the scene's, else 10)")
      ->check(CLI::Range(0, 1000));
  cmd->add_flag("--quiet,-q", options->quiet, "No progress and no summary");
  cmd->callback([options, exit_code] {
    if (SceneRobotKind(options->scene) != "arm") {
      throw InputError(SourceLocation{options->scene}, "twinsim ilc needs an arm scene (robot: arm)");
    }
    *exit_code = RunIlcCommand(*options);
  });
}

}  // namespace twinsim
