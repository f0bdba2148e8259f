#include "diagnosis/diagnosis_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/html_text.h"
#include "render/plot.h"

namespace twinsim {
namespace {

using nlohmann::ordered_json;

ordered_json Parameters(const std::map<std::string, double>& p) {
  ordered_json j = ordered_json::object();
  for (const auto& [k, v] : p) j[k] = v;
  return j;
}

ordered_json Joint(int joint) { return joint >= 0 ? ordered_json(joint + 1) : ordered_json(nullptr); }

std::string Num(double v, const char* format = "%.4g") {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string ParameterText(const std::map<std::string, double>& p) {
  std::string s;
  for (const auto& [k, v] : p) s += (s.empty() ? "" : ", ") + k + " = " + FormatParameter(v);
  return s;
}

// How far the repaired model closed the gap towards the noise floor (0..1, or NaN).
double ShareClosed(const DiagnosisReport& r) {
  const double room = r.gap_before - r.noise_floor;
  return room > 0 ? (r.gap_before - r.gap_after) / room : std::nan("");
}

}  // namespace

std::string DiagnosisVerdict(const DiagnosisReport& r) {
  const bool refit = std::isfinite(r.refit_gap);
  const std::string refitted = refit ? "Refitting the model's own parameters took the held-out gap from " +
                                           Num(r.gap_before) + " to " + Num(r.refit_gap) + ". "
                                     : std::string();
  if (r.effects.empty()) {
    return refitted + "Nothing significant is missing: no effect lowered the held-out gap (" +
           Num(refit ? r.refit_gap : r.gap_before) + ") by more than the noise allows (noise floor about " +
           Num(r.noise_floor) + ").";
  }
  std::string names;
  for (std::size_t k = 0; k < r.effects.size(); ++k) {
    if (k > 0) names += k + 1 == r.effects.size() ? " and " : ", ";
    names += EffectLabel(r.effects[k].name, r.effects[k].joint);
  }
  std::string s = refitted + "Missing: " + names + ". The held-out gap " + (r.gap_after <= r.gap_before ? "fell" : "rose") +
                  " from " + Num(r.gap_before) + " to " + Num(r.gap_after) +
                  " (noise floor about " + Num(r.noise_floor) + ")";
  const double closed = ShareClosed(r);
  if (std::isfinite(closed) && closed >= 0) s += ", " + Num(100 * closed, "%.0f") + " % of the way down to it";
  return s + ".";
}

std::string FormatDiagnosisJson(const DiagnosisReport& r) {
  ordered_json j;
  j["robot"] = r.robot;
  j["metric"] = r.metric;
  j["gap_before"] = r.gap_before;
  j["gap_after"] = r.gap_after;
  ordered_json effects = ordered_json::array();
  for (const DiagnosedEffect& e : r.effects) {
    ordered_json x;
    x["name"] = e.name;
    x["joint"] = Joint(e.joint);
    x["parameters"] = Parameters(e.parameters);
    x["gap_reduction"] = e.gap_reduction;
    x["evidence"] = e.evidence;
    effects.push_back(x);
  }
  j["effects"] = effects;
  // Beyond the contract: what a reader needs to judge the result.
  j["model"] = r.model_name;
  j["verdict"] = DiagnosisVerdict(r);
  j["noise_floor"] = r.noise_floor;
  if (std::isfinite(r.refit_gap)) j["refit_gap"] = r.refit_gap;
  j["fit_gap_before"] = r.fit_gap_before;
  j["fit_gap_after"] = r.fit_gap_after;
  j["held_out_share"] = r.held_out_share;
  j["block_seconds"] = r.block_seconds;
  j["fit_rows"] = r.fit_rows;
  j["held_out_rows"] = r.held_out_rows;
  j["logs"] = r.logs;
  ordered_json candidates = ordered_json::array();
  for (const DiagnosisCandidate& c : r.candidates) {
    ordered_json x;
    x["round"] = c.round;
    x["name"] = c.name;
    x["joint"] = Joint(c.joint);
    x["parameters"] = Parameters(c.parameters);
    x["fit_gap"] = c.fit_gap;
    x["held_out_gap"] = c.held_out_gap;
    x["reduction"] = std::isfinite(c.reduction) ? ordered_json(c.reduction) : ordered_json(nullptr);
    x["t_statistic"] = c.t_statistic;
    x["selected"] = c.selected;
    if (!c.note.empty()) x["note"] = c.note;
    candidates.push_back(x);
  }
  j["candidates"] = candidates;
  ordered_json findings = ordered_json::array();
  for (const ChannelFinding& f : r.findings) {
    ordered_json x;
    x["channel"] = f.channel;
    x["unit"] = f.unit;
    x["rms_before"] = f.rms;
    x["rms_after"] = f.rms_after;
    x["rms_near_reversal"] = f.rms_near_reversal;
    x["rms_moving"] = f.rms_moving;
    x["velocity_correlation"] = f.velocity_correlation;
    x["acceleration_correlation"] = f.acceleration_correlation;
    x["lag"] = f.lag;
    x["dominant_frequency"] = f.dominant_frequency;
    x["noise"] = f.noise;
    findings.push_back(x);
  }
  j["findings"] = findings;
  j["notes"] = r.notes;
  return j.dump(2) + "\n";
}

std::string FormatDiagnosisTable(const DiagnosisReport& r) {
  std::ostringstream s;
  s << DiagnosisVerdict(r) << "\n";
  s << "metric: " << r.metric << "\n";
  char line[256];
  std::snprintf(line, sizeof line, "held out: %.0f %% of %.3g s blocks (%d rows; %d for fitting)\n", 100 * r.held_out_share,
                r.block_seconds, r.held_out_rows, r.fit_rows);
  s << line;
  if (!r.effects.empty()) {
    std::snprintf(line, sizeof line, "%-34s %-9s %s\n", "effect", "gap cut", "parameters");
    s << line;
    for (const DiagnosedEffect& e : r.effects) {
      std::snprintf(line, sizeof line, "%-34s %6.1f %%  %s\n", EffectLabel(e.name, e.joint).c_str(), 100 * e.gap_reduction,
                    ParameterText(e.parameters).c_str());
      s << line;
    }
  }
  // Each round's three best candidates.
  int rounds = 0;
  for (const auto& c : r.candidates) rounds = std::max(rounds, c.round);
  for (int round = 1; round <= rounds; ++round) {
    std::vector<const DiagnosisCandidate*> cs;
    for (const auto& c : r.candidates) {
      if (c.round == round) cs.push_back(&c);
    }
    std::stable_sort(cs.begin(), cs.end(),
                     [](const DiagnosisCandidate* a, const DiagnosisCandidate* b) { return a->reduction > b->reduction; });
    s << "round " << round << ":";
    for (std::size_t k = 0; k < std::min<std::size_t>(3, cs.size()); ++k) {
      std::snprintf(line, sizeof line, "%s %s %.1f %% (t %.0f)%s", k ? "," : "", EffectLabel(cs[k]->name, cs[k]->joint).c_str(),
                    100 * std::max(-9.99, cs[k]->reduction), cs[k]->t_statistic, cs[k]->selected ? " added" : "");
      s << line;
    }
    s << "\n";
  }
  return s.str();
}

namespace {

// The nominal and the repaired model's residual of channel c against `x` (time or
// velocity), as lines or as dots.
SeriesPlot BeforeAfterPlot(const DiagnosisReport& r, std::size_t c, const std::vector<double>& x, bool points) {
  const ChannelFinding& f = r.findings[c];
  const ChannelSeries& s = r.series[c];
  SeriesPlot plot;
  plot.y_label = "measured - model [" + f.unit + "]";
  plot.series.push_back({"nominal model", x, s.before, points});
  plot.series.push_back({"repaired model", x, s.after, points});
  return plot;
}

SeriesPlot ResidualPlot(const DiagnosisReport& r, std::size_t c) {
  SeriesPlot plot = BeforeAfterPlot(r, c, r.series[c].t, false);
  plot.title = "Residual, " + r.findings[c].channel + ": nominal vs repaired model";
  plot.height = 420;
  return plot;
}

SeriesPlot VelocityPlot(const DiagnosisReport& r, std::size_t c) {
  SeriesPlot plot = BeforeAfterPlot(r, c, r.series[c].velocity, true);
  plot.title = "Residual against velocity, " + r.findings[c].channel;
  plot.x_label = r.robot == "arm" ? "joint velocity" : (c == 2 ? "turn rate [rad/s]" : "velocity [m/s]");
  plot.width = 700;
  plot.height = 520;
  return plot;
}

SeriesPlot SpectrumPlot(const DiagnosisReport& r, std::size_t c) {
  const ChannelFinding& f = r.findings[c];
  const ChannelSeries& s = r.series[c];
  SeriesPlot plot;
  plot.title = "Residual spectrum, " + f.channel;
  plot.x_label = "frequency [Hz]";
  plot.y_label = "PSD [dB " + f.unit + "^2/Hz]";
  plot.width = 700;
  plot.height = 520;
  auto db = [](const std::vector<double>& p) {
    std::vector<double> out;
    for (double v : p) out.push_back(10 * std::log10(std::max(v, 1e-30)));
    return out;
  };
  if (s.frequency.size() > 1) {
    std::vector<double> fr(s.frequency.begin() + 1, s.frequency.end());
    auto trim = [](std::vector<double> v) { return std::vector<double>(v.begin() + 1, v.end()); };
    plot.series.push_back({"nominal model", fr, trim(db(s.psd_before)), false});
    if (s.psd_after.size() == s.frequency.size()) plot.series.push_back({"repaired model", fr, trim(db(s.psd_after)), false});
  }
  return plot;
}

}  // namespace

std::string FormatDiagnosisHtml(const DiagnosisReport& r, Renderer& renderer) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Diagnosis: " << HtmlEscape(r.model_name)
    << "</title>\n<style>body{font-family:sans-serif;max-width:1250px;margin:2em auto;color:#222}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:left}"
       "th{background:#eee}.verdict{font-size:1.25em;padding:.7em;border-left:6px solid #0072B2;background:#f3f8fc}"
       ".sel{background:#e6f4ea}.small{color:#666;font-size:.9em}</style></head><body>\n";
  h << "<h1>Diagnosis of " << HtmlEscape(r.model_name) << " (" << HtmlEscape(r.robot) << ")</h1>\n";
  h << "<p class=\"verdict\">" << HtmlEscape(DiagnosisVerdict(r)) << "</p>\n";
  h << "<p>Gap: " << HtmlEscape(r.metric) << ". Held out: " << Num(100 * r.held_out_share, "%.0f") << " % of the "
    << Num(r.block_seconds, "%.3g") << " s time blocks of each log (" << r.held_out_rows << " rows), never seen by a fit ("
    << r.fit_rows << " rows). Logs:";
  for (const auto& l : r.logs) h << " <code>" << HtmlEscape(l) << "</code>";
  h << "</p>\n<table><tr><th></th><th>held-out gap</th><th>fit gap</th></tr>\n";
  h << "<tr><td>nominal model</td><td>" << Num(r.gap_before) << "</td><td>" << Num(r.fit_gap_before) << "</td></tr>\n";
  h << "<tr><td>repaired model</td><td>" << Num(r.gap_after) << "</td><td>" << Num(r.fit_gap_after) << "</td></tr>\n";
  h << "<tr><td>noise floor (estimated from the data)</td><td>" << Num(r.noise_floor) << "</td><td></td></tr></table>\n";

  if (!r.effects.empty()) {
    h << "<h2>Effects added</h2>\n<table><tr><th>effect</th><th>parameters</th><th>gap cut</th><th>evidence</th></tr>\n";
    for (const DiagnosedEffect& e : r.effects) {
      h << "<tr><td>" << HtmlEscape(EffectLabel(e.name, e.joint)) << "</td><td>" << HtmlEscape(ParameterText(e.parameters))
        << "</td><td>" << Num(100 * e.gap_reduction, "%.1f") << " %</td><td>" << HtmlEscape(e.evidence) << "</td></tr>\n";
    }
    h << "</table>\n";
  }

  if (!r.paths.empty()) {
    h << "<h2>Paths over a held-out stretch</h2>\n<p>The measured path and the free runs of the nominal and the repaired "
         "model from the same measured state and under the same logged commands (seed 000, Fig. 4).</p>\n";
    PathPlot plot;
    plot.title = "Measured, nominal and repaired paths";
    plot.width = 1000;
    plot.height = 750;
    for (const DiagnosisPath& p : r.paths) {
      PlotPath path;
      path.name = p.name;
      for (std::size_t i = 0; i < p.x.size(); ++i) path.poses.push_back({p.x[i], p.y[i], p.theta[i]});
      plot.paths.push_back(path);
    }
    h << HtmlImage(RenderPathPlot(plot, renderer), "paths") << "\n";
  }

  h << "<h2>Where the model and the measurement disagree</h2>\n<table><tr><th>channel</th><th>RMS before</th>"
       "<th>RMS after</th><th>near reversals / stops</th><th>moving</th><th>corr. with velocity</th>"
       "<th>corr. with acceleration</th><th>lag [ms]</th><th>spectral peak [Hz]</th><th>noise</th></tr>\n";
  for (const ChannelFinding& f : r.findings) {
    h << "<tr><td>" << HtmlEscape(f.channel) << "</td><td>" << Num(f.rms) << "</td><td>" << Num(f.rms_after) << "</td><td>"
      << Num(f.rms_near_reversal) << "</td><td>" << Num(f.rms_moving) << "</td><td>" << Num(f.velocity_correlation, "%.2f")
      << "</td><td>" << Num(f.acceleration_correlation, "%.2f") << "</td><td>" << Num(1000 * f.lag, "%.1f") << "</td><td>"
      << Num(f.dominant_frequency, "%.3g") << "</td><td>" << Num(f.noise) << "</td></tr>\n";
  }
  h << "</table>\n<p class=\"small\">Lag: arm, the shift that best aligns the logged command with the model's; omni, "
       "how much later than the nominal model the measured velocity follows the command. Both positive when the "
       "real system is late.</p>\n";
  for (std::size_t c = 0; c < r.findings.size() && c < r.series.size(); ++c) {
    h << "<h3>" << HtmlEscape(r.findings[c].channel) << "</h3>\n";
    h << HtmlImage(RenderSeriesPlot(ResidualPlot(r, c), renderer), "residual over time") << "<br>\n";
    h << HtmlImage(RenderSeriesPlot(VelocityPlot(r, c), renderer), "residual against velocity") << "\n";
    h << HtmlImage(RenderSeriesPlot(SpectrumPlot(r, c), renderer), "residual spectrum") << "\n";
  }

  h << "<h2>Every candidate tried</h2>\n<p>Each round fits every remaining candidate with the effects already added, "
       "scores it on the held-out blocks, and adds the best if it removes at least the required share of the held-out "
       "squared error with a t statistic over chunks of held-out data above the threshold.</p>\n"
       "<table><tr><th>round</th><th>candidate</th><th>fitted parameters</th><th>fit gap</th><th>held-out gap</th>"
       "<th>share of squared error removed</th><th>t</th><th></th></tr>\n";
  for (const DiagnosisCandidate& c : r.candidates) {
    h << "<tr" << (c.selected ? " class=\"sel\"" : "") << "><td>" << c.round << "</td><td>" << HtmlEscape(EffectLabel(c.name, c.joint))
      << "</td><td>" << HtmlEscape(ParameterText(c.parameters)) << "</td><td>" << Num(c.fit_gap) << "</td><td>"
      << Num(c.held_out_gap) << "</td><td>" << (std::isfinite(c.reduction) ? Num(100 * c.reduction, "%.2f") + " %" : "")
      << "</td><td>" << Num(c.t_statistic, "%.1f") << "</td><td>" << (c.selected ? "added" : HtmlEscape(c.note)) << "</td></tr>\n";
  }
  h << "</table>\n";
  if (!r.notes.empty()) {
    h << "<h2>Notes</h2><ul>\n";
    for (const auto& n : r.notes) h << "<li>" << HtmlEscape(n) << "</li>\n";
    h << "</ul>\n";
  }
  h << "<p class=\"small\">twinsim diagnose; method: docs/diagnose.md.</p>\n</body></html>\n";
  return h.str();
}

}  // namespace twinsim
