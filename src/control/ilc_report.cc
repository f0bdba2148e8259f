#include "control/ilc_report.h"

#include <cmath>
#include <complex>
#include <sstream>

#include "control/tracking_plots.h"
#include "core/math_constants.h"
#include "io/base64.h"
#include "io/csv_table.h"
#include "io/html_text.h"
#include "render/image_stack.h"
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
  std::string out = "joint,posture,frequency,magnitude,phase,filter_magnitude,filter_phase\n";
  for (std::size_t j = 0; j < frf.response.size(); ++j) {
    for (std::size_t p = 0; p < frf.response[j].size(); ++p) {
      for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
        const std::complex<double> ps = frf.response[j][p][i];
        const std::complex<double> inv = 1.0 / filters[j].Response(frf.frequency[i], frf.sample_time);
        out += std::to_string(j + 1) + ',' + std::to_string(p + 1) + ',' + Num(frf.frequency[i]) + ',' +
               Num(std::abs(ps)) + ',' + Num(std::arg(ps) * 180 / kPi) + ',' + Num(std::abs(inv)) + ',' +
               Num(std::arg(inv) * 180 / kPi) + '\n';
      }
    }
  }
  return out;
}

std::string FormatIlcFiltersCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters,
                                const IlcOptions& o) {
  std::string out =
      "joint,shift,inertia,inertia_early,damping,stiffness,residual,learning_limit_hz,q_order,q_cutoff,worst_factor\n";
  for (std::size_t j = 0; j < filters.size(); ++j) {
    const LearningFilter& l = filters[j];
    const double limit = LearningLimitFrequency(frf, static_cast<int>(j), l, o.gain);
    out += std::to_string(j + 1) + ',' + std::to_string(l.shift) + ',' + Num(l.inertia) + ',' + Num(l.inertia_early) +
           ',' + Num(l.damping) + ',' + Num(l.stiffness) + ',' + Num(l.residual) + ',' +
           (std::isfinite(limit) ? Num(limit) : std::string()) + ',' + std::to_string(o.q_order) + ',' +
           Num(o.q_cutoff) + ',' + Num(ConvergenceFactor(frf, static_cast<int>(j), l, o).maxCoeff()) + '\n';
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

IlcBodePlot IlcBodePlots(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title) {
  IlcBodePlot bode;
  SeriesPlot& mag = bode.magnitude;
  SeriesPlot& phase = bode.phase;
  mag.title = title;
  mag.x_label = phase.x_label = "log10(f / Hz)";
  mag.y_label = "|PS| [dB re 1 rad/(N m)]";
  phase.y_label = "phase [deg]";
  mag.height = phase.height = 450;
  const auto& responses = frf.response.at(static_cast<std::size_t>(joint));
  for (std::size_t p = 0; p <= responses.size(); ++p) {
    PlotSeries m, ph;
    m.name = ph.name = p < responses.size() ? "posture " + std::to_string(p + 1) : "1 / L (learning filter)";
    std::vector<double> wrapped;
    for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
      const std::complex<double> v =
          p < responses.size() ? responses[p][i] : 1.0 / filter.Response(frf.frequency[i], frf.sample_time);
      wrapped.push_back(std::arg(v) * 180 / kPi);
      m.x.push_back(std::log10(frf.frequency[i]));
      ph.x.push_back(std::log10(frf.frequency[i]));
      m.y.push_back(20 * std::log10(std::abs(v)));
    }
    ph.y = UnwrapDegrees(wrapped);
    mag.series.push_back(m);
    phase.series.push_back(ph);
  }
  return bode;
}

RgbaImage RenderIlcBodePlot(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title,
                            Renderer& renderer) {
  const IlcBodePlot bode = IlcBodePlots(frf, filter, joint, title);
  return StackImages(RenderSeriesPlot(bode.magnitude, renderer), RenderSeriesPlot(bode.phase, renderer));
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
       << " s averaged after one transient period).</p>\n";
  // The Bode plots follow the convergence and error plots in `images`.
  for (int j = 0; j < n && !images.empty(); ++j) {
    html << "<img src=\"data:image/png;base64," << Base64Encode(images[2 + j].second) << "\" alt=\"Bode plot joint "
         << j + 1 << "\">\n";
  }
  html << "<h2>2. Filters</h2>\n<p>Learning filter L (" << HtmlEscape(setup.learning_filter)
       << "): L(z) = (a2 z^&tau; + a2' z^(&tau;+1)) (z &minus; 2 + 1/z)/Ts&sup2; + a1 (z &minus; 1/z)/(2Ts) + a0, applied "
          "offline (non-causal). Robustness filter Q: "
       << (o.q_order > 0 ? "zero-phase Butterworth, order " + std::to_string(o.q_order) + ", cut-off " +
                               Num(o.q_cutoff) + " Hz"
                         : std::string("none"))
       << ". Update f<sub>k+1</sub> = Q(f<sub>k</sub> + " << Num(o.gain)
       << " L e<sub>k</sub>).</p>\n<table><tr><th>joint</th><th>&tau; [samples]</th><th>a2 + a2' [kg m&sup2;]</th>"
          "<th>a1 [N m s/rad]</th><th>a0 [N m/rad]</th><th>fit residual</th><th>|1 &minus; &alpha; PS L| &lt; 1 up to [Hz]</th>"
          "<th>worst |Q|&sup2;|1 &minus; &alpha; PS L|</th></tr>\n";
  for (int j = 0; j < n; ++j) {
    const double limit = LearningLimitFrequency(frf, j, filters[j], o.gain);
    html << "<tr><td>" << j + 1 << "</td><td>" << filters[j].shift << "</td><td>"
         << Num(filters[j].inertia + filters[j].inertia_early) << "</td><td>" << Num(filters[j].damping) << "</td><td>"
         << Num(filters[j].stiffness) << "</td><td>" << Num(filters[j].residual) << "</td><td>"
         << (std::isfinite(limit) ? Num(limit) : std::string("all")) << "</td><td>"
         << Num(ConvergenceFactor(frf, j, filters[j], o).maxCoeff()) << "</td></tr>\n";
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
  std::vector<std::pair<std::string, std::string>> files = {
      {"trials.csv", FormatIlcTrialsCsv(result)},
      {"frf.csv", FormatIlcFrfCsv(frf, filters)},
      {"filters.csv", FormatIlcFiltersCsv(frf, filters, setup.options)},
      {"feedforward.csv", JointColumnsCsv(t, {"f"}, {&result.feedforward})},
  };
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
    images.emplace_back("path.png", EncodePng(RenderPathPlot(
                                        IlcToolPathPlot(result, plant, setup.tool, what + ": tool path"), *renderer)));
  }
  files.insert(files.end(), images.begin(), images.end());
  files.emplace_back("report.html", FormatIlcReportHtml(setup, plant, frf, filters, result, images));
  return files;
}

}  // namespace twinsim
