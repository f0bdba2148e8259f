#include "control/ilc_report.h"

#include <cmath>
#include <complex>
#include <functional>
#include <sstream>

#include "control/tracking_plots.h"
#include "core/math_constants.h"
#include "io/base64.h"
#include "io/csv_table.h"
#include "io/html_text.h"
#include "render/image_stack.h"
#include "signal/butterworth.h"
#include "signal/phase_unwrap.h"

namespace twinsim {
namespace {

std::string Num(double v) { return FormatCsvNumber(v); }

}  // namespace

std::string FormatIlcTrialsCsv(const IlcResult& r) {
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

std::string FormatIlcFrfCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters) {
  std::string out = "joint,posture,frequency,magnitude,phase,coherence,filter_magnitude,filter_phase\n";
  for (std::size_t j = 0; j < frf.response.size(); ++j) {
    const Eigen::VectorXcd nominal = frf.Nominal(static_cast<int>(j));
    const Eigen::VectorXd worst = frf.WorstCoherence(static_cast<int>(j));
    // Posture 0 is the nominal response, the average over the postures, with the worst coherence.
    for (std::size_t p = 0; p <= frf.response[j].size(); ++p) {
      for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
        const std::complex<double> ps = p == 0 ? nominal[i] : frf.response[j][p - 1][i];
        const double coherence = p == 0 ? worst[i]
                                 : j < frf.coherence.size() && p - 1 < frf.coherence[j].size() ? frf.coherence[j][p - 1][i]
                                                                                                   : 1.0;
        const std::complex<double> inv = 1.0 / filters[j].Response(frf.frequency[i], frf.sample_time);
        out += std::to_string(j + 1) + ',' + std::to_string(p) + ',' + Num(frf.frequency[i]) + ',' +
               Num(std::abs(ps)) + ',' + Num(std::arg(ps) * 180 / kPi) + ',' + Num(coherence) + ',' +
               Num(std::abs(inv)) + ',' + Num(std::arg(inv) * 180 / kPi) + '\n';
      }
    }
  }
  return out;
}

std::string FormatIlcFiltersCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters,
                                const IlcOptions& o) {
  std::string out =
      "joint,shift,model_order,inertia,inertia_early,snap,damping,stiffness,residual,fit_lines,fit_min_hz,fit_max_hz,"
      "learning_limit_hz,q_order,q_cutoff,worst_factor,margin\n";
  for (std::size_t j = 0; j < filters.size(); ++j) {
    const LearningFilter& l = filters[j];
    const int joint = static_cast<int>(j);
    const double limit = LearningLimitFrequency(frf, joint, l, o.gain);
    const double worst = ConvergenceFactor(frf, joint, l, o).maxCoeff();
    out += std::to_string(j + 1) + ',' + std::to_string(l.shift) + ',' + std::to_string(l.order) + ',' + Num(l.inertia) +
           ',' + Num(l.inertia_early) + ',' + Num(l.snap) + ',' + Num(l.damping) + ',' + Num(l.stiffness) + ',' + Num(l.residual) + ',' + std::to_string(l.lines) + ',' +
           (l.lines > 0 ? Num(l.band_min) + ',' + Num(l.band_max) : std::string(",")) + ',' +
           (std::isfinite(limit) ? Num(limit) : std::string()) + ',' + std::to_string(o.q_order) + ',' +
           Num(o.Cutoff(joint)) + ',' + Num(worst) + ',' + Num(1 - worst) + '\n';
  }
  return out;
}

SeriesPlot IlcConvergencePlot(const IlcResult& r, const std::string& title) {
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

SeriesPlot IlcErrorPlot(const IlcResult& r, const std::string& title) {
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

namespace {

constexpr std::uint32_t kGrey = 0xb0b0b0;

// A series of 20 log10 |v(f)| against log10 f.
PlotSeries DecibelSeries(const std::string& name, const Eigen::VectorXd& frequency,
                         const std::function<std::complex<double>(Eigen::Index)>& v) {
  PlotSeries s;
  s.name = name;
  for (Eigen::Index i = 0; i < frequency.size(); ++i) {
    s.x.push_back(std::log10(frequency[i]));
    s.y.push_back(20 * std::log10(std::abs(v(i))));
  }
  return s;
}

// The same series greyed out, only the first of a group in the legend.
PlotSeries Grey(PlotSeries s, bool first) {
  s.color = kGrey;
  s.legend = first;
  return s;
}

// Two panels against log10 f, 450 px high each, the title on the upper one.
IlcBodePlot TwoPanels(const std::string& title, const std::string& top_label, const std::string& bottom_label) {
  IlcBodePlot plots;
  plots.magnitude.title = title;
  plots.magnitude.x_label = plots.phase.x_label = "log10(f / Hz)";
  plots.magnitude.y_label = top_label;
  plots.phase.y_label = bottom_label;
  plots.magnitude.height = plots.phase.height = 450;
  return plots;
}

// Both panels drawn, the upper stacked above the lower.
RgbaImage RenderPanels(const IlcBodePlot& plots, Renderer& renderer) {
  return StackImages(RenderSeriesPlot(plots.magnitude, renderer), RenderSeriesPlot(plots.phase, renderer));
}

}  // namespace

IlcBodePlot IlcBodePlots(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title) {
  IlcBodePlot bode = TwoPanels(title, "|PS| [dB re 1 rad/(N m)]", "phase [deg]");
  SeriesPlot& mag = bode.magnitude;
  SeriesPlot& phase = bode.phase;
  const auto& responses = frf.response.at(static_cast<std::size_t>(joint));
  const Eigen::VectorXcd nominal = frf.Nominal(joint);
  // The postures in grey (seed 001, Fig. 8), the nominal response and the fitted model 1/L (Fig. 9).
  for (std::size_t p = 0; p <= responses.size() + 1; ++p) {
    std::function<std::complex<double>(Eigen::Index)> v;
    std::string name;
    if (p < responses.size()) {
      v = [&, p](Eigen::Index i) { return responses[p][i]; };
      name = std::to_string(responses.size()) + " postures";
    } else if (p == responses.size()) {
      v = [&](Eigen::Index i) { return nominal[i]; };
      name = "nominal (their average)";
    } else {
      v = [&](Eigen::Index i) { return 1.0 / filter.Response(frf.frequency[i], frf.sample_time); };
      name = "1 / L (learning filter)";
    }
    PlotSeries m = DecibelSeries(name, frf.frequency, v), ph = m;
    std::vector<double> wrapped;
    for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) wrapped.push_back(std::arg(v(i)) * 180 / kPi);
    ph.y = UnwrapDegrees(wrapped);
    if (p < responses.size()) m = Grey(m, p == 0), ph = Grey(ph, p == 0);
    mag.series.push_back(m);
    phase.series.push_back(ph);
  }
  return bode;
}

RgbaImage RenderIlcBodePlot(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title,
                            Renderer& renderer) {
  return RenderPanels(IlcBodePlots(frf, filter, joint, title), renderer);
}

IlcBodePlot IlcCriterionPlots(const ClosedLoopFrf& frf, const LearningFilter& filter, const IlcOptions& options,
                              int joint, const std::string& title) {
  IlcBodePlot plots = TwoPanels(title, "[dB re 1 N m/rad]", "[dB]");
  SeriesPlot& top = plots.magnitude;
  SeriesPlot& bottom = plots.phase;
  const auto& responses = frf.response.at(static_cast<std::size_t>(joint));
  const double ts = frf.sample_time;
  const Eigen::VectorXd& f = frf.frequency;
  // Seed 001, Fig. 10: L against the inverse process sensitivities, then the products
  // |1 - gain PS_i L| against 1/|Q|^2, below which learning converges.
  for (std::size_t p = 0; p < responses.size(); ++p) {
    top.series.push_back(Grey(DecibelSeries("1 / PS at the postures", f, [&](Eigen::Index i) { return 1.0 / responses[p][i]; }),
                              p == 0));
    bottom.series.push_back(Grey(DecibelSeries("|1 - gain PS L| at the postures", f,
                                               [&](Eigen::Index i) {
                                                 return 1.0 - options.gain * responses[p][i] * filter.Response(f[i], ts);
                                               }),
                                 p == 0));
  }
  top.series.push_back(DecibelSeries("L", f, [&](Eigen::Index i) { return filter.Response(f[i], ts); }));
  if (options.q_order > 0) {
    const ButterworthFilter q = DesignButterworthLowPass(options.q_order, options.Cutoff(joint), 1 / ts);
    bottom.series.push_back(DecibelSeries("1 / |Q|^2 (Q at " + Num(options.Cutoff(joint)) + " Hz)", f, [&](Eigen::Index i) {
      return std::complex<double>(1 / std::norm(FrequencyResponse(q, f[i])));
    }));
  } else {
    bottom.series.push_back(DecibelSeries("1 (no Q)", f, [](Eigen::Index) { return std::complex<double>(1); }));
  }
  return plots;
}

std::string FormatIlcSafeguardCsv(const IlcResult& result) {
  std::string csv = "trial,joint,action,rms,best_rms,best_trial,q_cutoff\n";
  for (const IlcSafeguardEvent& e : result.safeguard) {
    csv += std::to_string(e.trial) + "," + std::to_string(e.joint + 1) + "," + e.action + "," + Num(e.rms) + "," +
           Num(e.best_rms) + "," + std::to_string(e.best_trial) + "," + Num(e.cutoff) + "\n";
  }
  return csv;
}

std::string IlcSafeguardSummary(const IlcResult& result, const IlcOptions& options) {
  const int last = static_cast<int>(result.error_rms.size()) - 1;
  std::ostringstream s;
  s.precision(3);
  if (options.safeguard.growth <= 0) {
    s << "Off (ilc.safeguard: off): nothing watched the trials.";
  } else {
    s << "After each trial every joint's RMS error is compared with its best so far; above " << options.safeguard.growth
      << " times it for " << options.safeguard.patience
      << " trial(s) in a row, the joint's feedforward goes back to that of its best trial and its Q cut-off is "
         "multiplied by "
      << options.safeguard.cutoff_factor << ", at most " << options.safeguard.lowerings << " time(s) (then, below "
      << options.safeguard.min_cutoff
      << " Hz, or with no Q, the joint stops learning; a stopped joint that grows again through the others sends "
         "every joint back to the best trial's feedforward and ends learning). ";
    if (result.safeguard.empty()) {
      s << "It never acted.";
    } else {
      s << "It acted " << result.safeguard.size() << " time(s); Q's cut-offs at the end:";
      for (Eigen::Index j = 0; j < result.final_cutoffs.size(); ++j) {
        s << (j ? ", " : " ") << "joint " << j + 1 << " "
          << (result.final_cutoffs[j] > 0 ? Num(result.final_cutoffs[j]) + " Hz" : std::string("stopped"));
      }
      s << ".";
    }
  }
  s << " Best trial " << result.best_trial << " (the worst joint's error relative to trial 0 lowest), its feedforward in "
    << "best_feedforward.csv; the last trial (" << last << ") stands at";
  for (Eigen::Index j = 0; j < result.error_rms.front().size(); ++j) {
    double best = INFINITY;
    for (const Eigen::VectorXd& r : result.error_rms) best = std::min(best, r[j]);
    s << (j ? "," : "") << " " << result.error_rms[static_cast<std::size_t>(last)][j] / best << "x";
  }
  s << " each joint's best.";
  return s.str();
}

PathPlot IlcToolPathPlot(const IlcResult& result, const ArmModel& plant, const Eigen::Vector3d& tool,
                         const std::string& title) {
  PathPlot path = ToolPathPlot(result.first, plant, tool, title);
  path.paths[1].name = "trial 0";
  PathPlot last = ToolPathPlot(result.last, plant, tool, "");
  last.paths[1].name = "trial " + std::to_string(result.error_rms.size() - 1);
  path.paths.push_back(last.paths[1]);
  return path;
}

std::string FormatIlcReportHtml(const IlcReportSetup& setup, const ArmModel& plant, const ClosedLoopFrf& frf,
                                const std::vector<LearningFilter>& filters, const IlcResult& result,
                                const std::vector<std::pair<std::string, std::string>>& images) {
  // The story from the FRFs through the filters to the convergence.
  const IlcOptions& o = setup.options;
  const int n = static_cast<int>(filters.size());
  std::ostringstream html;
  const int last = static_cast<int>(result.error_rms.size()) - 1;
  html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>ILC: " << HtmlEscape(setup.name)
       << "</title>\n<style>body{font-family:sans-serif;max-width:1250px;margin:auto}"
          "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
          "img{max-width:100%}</style></head><body>\n";
  html << "<h1>Iterative learning control: " << HtmlEscape(setup.name) << "</h1>\n";
  html << "<p>Plant <b>" << HtmlEscape(plant.name) << "</b>, controller "
       << HtmlEscape(TrackingControllerName(setup.tracking.controller)) << " with model <b>" << HtmlEscape(setup.hat)
       << "</b> at " << setup.tracking.bandwidth << " Hz, backend " << HtmlEscape(setup.backend) << ". " << last
       << " learning trials after trial 0 (no learning): the worst joint's RMS error went from "
       << Num(result.WorstRms(0)) << " rad to " << Num(result.WorstRms(last)) << " rad, <b>" << Num(result.Reduction())
       << " times smaller</b>" << (result.Diverged() ? " &mdash; <b>the learning diverged</b>" : "")
       << ".</p>\n";  // no wall time here: the same scene gives the same bytes (stdout has it)
  html << "<h2>1. Process sensitivity</h2>\n<p>PS = q / f, from a feedforward torque added to the controller's output to "
          "the joint position with the feedback closed, measured per joint at "
       << frf.postures.size() << " postures by a random-phase multisine (" << Num(setup.frf.f_min) << "&ndash;"
       << Num(setup.frf.f_max) << " Hz, " << setup.frf.periods << " periods of " << Num(setup.frf.period)
       << " s averaged after one transient period). In grey every posture's, then their average, the nominal "
          "process sensitivity (seed 001, eq. 23 and Fig. 8), and 1/L, the model the learning filter inverts (Fig. "
          "9): the controller's known feedback plus the plant's inertia and delay (and, at model order 4, a series "
          "spring's snap term) fitted to the nominal response "
          "(learning filter &ldquo;fitted&rdquo;) or taken from the controller's model (&ldquo;model&rdquo;). "
          "frf.csv has every line with its coherence (posture 0 is the nominal).</p>\n";
  auto embed = [&](const std::string& prefix) {
    for (const auto& [file, png] : images) {
      if (file.rfind(prefix, 0) != 0) continue;
      html << "<img src=\"data:image/png;base64," << Base64Encode(png) << "\" alt=\"" << HtmlEscape(file) << "\">\n";
    }
  };
  embed("bode");
  html << "<h2>2. Filters</h2>\n<p>Learning filter L (" << HtmlEscape(setup.learning_filter)
       << "): L(z) = (a2 z^&tau; + a2' z^(&tau;+1)) (z &minus; 2 + 1/z)/Ts&sup2; + a4 (z^&tau; + z^(&tau;+1))/2 "
          "(z &minus; 2 + 1/z)&sup2;/Ts&#8308; + a1 (z &minus; 1/z)/(2Ts) + a0 (a4 = 0 at model order 2), applied "
          "offline (non-causal). Robustness filter Q: "
       << (o.q_order > 0 ? "zero-phase Butterworth, order " + std::to_string(o.q_order) +
                               (o.q_cutoffs.empty() ? ", cut-off " + Num(o.q_cutoff) + " Hz for every joint"
                                                    : std::string(", each joint's cut-off the highest for which "
                                                                  "|Q|&sup2;|1 &minus; &alpha; PS<sub>i</sub> L| &lt; 1 "
                                                                  "at every measured posture i"))
                         : std::string("none"))
       << ". Update f<sub>k+1</sub> = Q(f<sub>k</sub> + " << Num(o.gain)
       << (o.update == "norm_optimal"
               ? std::string(" S e<sub>k</sub>), S = (I + w L L<sup>T</sup>)<sup>&minus;1</sup> L, the norm-optimal step "
                             "(L/(1 + w|L|&sup2;) in frequency; w = 1/|L(f<sub>b</sub>)|&sup2;, f<sub>b</sub> = ") +
                     (o.norm_optimal_bandwidth > 0 ? Num(o.norm_optimal_bandwidth) + " Hz" : std::string("each joint's Q cut-off")) + ")"
               : std::string(" L e<sub>k</sub>)"))
       << ".</p>\n<table><tr><th>joint</th><th>&tau; [samples]</th><th>a2 + a2' [kg m&sup2;]</th>"
          "<th>a4 [kg m&sup2; s&sup2;]</th><th>a1 [N m s/rad]</th><th>a0 [N m/rad]</th><th>fit residual</th><th>|1 &minus; &alpha; PS L| &lt; 1 up to [Hz]</th>"
          "<th>Q cut-off [Hz]</th><th>worst |Q|&sup2;|1 &minus; &alpha; PS S| (S the step: L, or the norm-optimal step)</th></tr>\n";
  for (int j = 0; j < n; ++j) {
    const double limit = LearningLimitFrequency(frf, j, filters[j], o.gain);
    html << "<tr><td>" << j + 1 << "</td><td>" << filters[j].shift << "</td><td>"
         << Num(filters[j].inertia + filters[j].inertia_early) << "</td><td>" << Num(filters[j].snap) << "</td><td>"
         << Num(filters[j].damping) << "</td><td>"
         << Num(filters[j].stiffness) << "</td><td>" << Num(filters[j].residual) << "</td><td>"
         << (std::isfinite(limit) ? Num(limit) : std::string("all")) << "</td><td>"
         << (o.q_order > 0 ? Num(o.Cutoff(j)) : std::string("none")) << "</td><td>"
         << Num(ConvergenceFactor(frf, j, filters[j], o).maxCoeff()) << "</td></tr>\n";
  }
  html << "</table>\n<p>Below, per joint, L against the inverse process sensitivities of the postures, and the "
          "products |1 &minus; &alpha; PS<sub>i</sub> L| against 1/|Q|&sup2;: learning converges where the grey lines "
          "stay below it (seed 001, Fig. 10).</p>\n";
  embed("criterion");
  html << "<h2>3. Convergence</h2>\n<table><tr><th>trial</th>";
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
  html << "<h2>4. Safeguard</h2>\n<p>" << HtmlEscape(IlcSafeguardSummary(result, o)) << "</p>\n";
  if (!result.safeguard.empty()) {
    html << "<table><tr><th>trial</th><th>joint</th><th>RMS [mrad]</th><th>its best [mrad]</th><th>back to trial</th>"
            "<th>Q cut-off now [Hz]</th></tr>\n";
    for (const IlcSafeguardEvent& e : result.safeguard) {
      html << "<tr><td>" << e.trial << "</td><td>" << e.joint + 1 << "</td><td>" << Num(1e3 * e.rms) << "</td><td>"
           << Num(1e3 * e.best_rms) << "</td><td>" << e.best_trial << "</td><td>"
           << (e.action == "stop_all" ? std::string("every joint back to the best trial; learning ended")
               : e.cutoff > 0       ? Num(e.cutoff)
                                    : std::string("stopped learning"))
           << "</td></tr>\n";
    }
    html << "</table>\n";
  }
  for (const auto& [file, png] : images) {
    if (file.rfind("bode", 0) == 0 || file.rfind("criterion", 0) == 0) continue;
    html << "<p><img src=\"data:image/png;base64," << Base64Encode(png) << "\" alt=\"" << HtmlEscape(file)
         << "\"></p>\n";
  }
  html << "</body></html>\n";
  return html.str();
}

std::vector<std::pair<std::string, std::string>> MakeIlcReport(const IlcReportSetup& setup, const ArmModel& plant,
                                                               const Eigen::VectorXd& t, const ClosedLoopFrf& frf,
                                                               const std::vector<LearningFilter>& filters,
                                                               const IlcResult& result, Renderer* renderer) {
  // The tracking error of trial 0 and of the last trial, sample by sample (rad or m).
  const Eigen::MatrixXd first_error = result.first.q_ref - result.first.q;
  const Eigen::MatrixXd last_error = result.last.q_ref - result.last.q;
  const bool have_errors = first_error.rows() == t.size() && last_error.rows() == t.size() && t.size() > 0;
  std::vector<std::pair<std::string, std::string>> files = {
      {"trials.csv", FormatIlcTrialsCsv(result)},
      {"frf.csv", FormatIlcFrfCsv(frf, filters)},
      {"filters.csv", FormatIlcFiltersCsv(frf, filters, setup.options)},
      {"feedforward.csv", JointColumnsCsv(t, {"f"}, {&result.feedforward})},
      {"best_feedforward.csv", JointColumnsCsv(t, {"f"}, {&result.best_feedforward})},
      {"safeguard.csv", FormatIlcSafeguardCsv(result)},
  };
  if (have_errors) files.emplace_back("errors.csv", JointColumnsCsv(t, {"first_e", "last_e"}, {&first_error, &last_error}));
  std::vector<std::pair<std::string, std::string>> images;  // file, PNG bytes
  if (renderer) {
    const std::string what = setup.name + " (" + setup.backend + ")";
    images.emplace_back("convergence.png",
                        EncodePng(RenderSeriesPlot(IlcConvergencePlot(result, what + ": tracking error per trial"),
                                                   *renderer)));
    images.emplace_back("error.png", EncodePng(RenderSeriesPlot(
                                         IlcErrorPlot(result, what + ": tracking error, first and last trial"),
                                         *renderer)));
    for (int j = 0; j < static_cast<int>(filters.size()); ++j) {
      images.emplace_back("bode_joint" + std::to_string(j + 1) + ".png",
                          EncodePng(RenderIlcBodePlot(
                              frf, filters[static_cast<std::size_t>(j)], j,
                              what + ": process sensitivity, joint " + std::to_string(j + 1), *renderer)));
    }
    for (int j = 0; j < static_cast<int>(filters.size()); ++j) {
      const IlcBodePlot c = IlcCriterionPlots(frf, filters[static_cast<std::size_t>(j)], setup.options, j,
                                              what + ": learning filter and convergence, joint " + std::to_string(j + 1));
      images.emplace_back("criterion_joint" + std::to_string(j + 1) + ".png", EncodePng(RenderPanels(c, *renderer)));
    }
    images.emplace_back("path.png", EncodePng(RenderPathPlot(
                                        IlcToolPathPlot(result, plant, setup.tool, what + ": tool path"), *renderer)));
  }
  files.insert(files.end(), images.begin(), images.end());
  files.emplace_back("report.html", FormatIlcReportHtml(setup, plant, frf, filters, result, images));
  return files;
}

}  // namespace twinsim
