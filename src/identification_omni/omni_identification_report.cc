// report.json, the terminal table and report.html of an omni identification.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "analysis/omni_calibration_report.h"
#include "analysis/omni_horizons.h"
#include "identification_omni/omni_identification.h"
#include "io/html_text.h"
#include "io/printf_number.h"
#include "render/plot.h"

namespace twinsim {
namespace {

using ordered_json = nlohmann::ordered_json;

std::string Number(double v, const char* format = "%.4g") {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

ordered_json Finite(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); }

// A noise parameter on its search's bound, said after its unit (issue 64: no bound the
// data hits without saying so).
std::string NoiseBoundNote(const OmniNoiseParameter& p) {
  if (p.bound == "lower") return "  (at its lower bound: the logs ask for less)";
  if (p.bound == "upper") return "  (at its upper bound: the logs ask for more)";
  return "";
}

ordered_json GapsJson(const std::vector<OmniGap>& gaps) {
  ordered_json out = ordered_json::array();
  for (const OmniGap& g : gaps) {
    ordered_json x;
    x["name"] = g.name;
    x["position_rmse"] = g.rmse;
    x["pose_rms"] = g.pose;
    x["forward_rms"] = g.forward;
    x["sideways_rms"] = g.sideways;
    x["turn_rms"] = g.turn;
    out.push_back(x);
  }
  return out;
}

// The rows the report's calibration is on: a noise fitted on the held-out blocks is
// judged there only across their halves.
std::string CalibratedOn(const OmniIdentificationReport& r) {
  if (!r.validation.empty()) return "validation logs";
  return r.noise.kept ? "held-out blocks, each half with the noise fitted on the other" : "held-out blocks";
}

ordered_json NoiseJson(const OmniIdentificationReport& r) {
  const OmniNoiseIdentification& n = r.noise;
  ordered_json j;
  j["identified"] = r.noise_identified;
  if (!r.noise_identified) return j;
  j["kept"] = n.kept;
  j["simulated"] = true;  // the identified model draws it in run and serve
  j["fit_log_score_before"] = Finite(n.fit_before);
  j["fit_log_score_after"] = Finite(n.fit_after);
  j["held_out_log_score_before"] = Finite(n.held_out_before);
  j["held_out_log_score_after"] = Finite(n.held_out_after);
  j["fit_rows"] = n.fit_rows;
  j["held_out_rows"] = n.held_out_rows;
  j["evaluations"] = n.evaluations;
  ordered_json params = ordered_json::array();
  for (const OmniNoiseParameter& p : n.parameters) {
    params.push_back({{"name", p.name}, {"unit", p.unit}, {"start", p.start}, {"value", p.value},
                      {"standard_error", Finite(p.standard_error)}});
    if (!p.bound.empty()) params.back()["at_bound"] = p.bound;
  }
  j["parameters"] = params;
  if (!n.note.empty()) j["note"] = n.note;
  if (!n.growth_note.empty()) j["growth_note"] = n.growth_note;
  if (r.drift_identified) {
    const OmniDriftIdentification& d = r.drift;
    ordered_json drift;
    drift["kept"] = d.kept;
    drift["fitted_on"] = d.on;
    drift["forward"] = d.drift.sd[0];
    drift["sideways"] = d.drift.sd[1];
    drift["turn"] = d.drift.sd[2];
    drift["correlation_time"] = d.drift.correlation_time;
    constexpr const char* kNames[4] = {"forward", "sideways", "turn", "correlation_time"};
    ordered_json se, bound;
    for (std::size_t k = 0; k < 4; ++k) {
      if (!std::isnan(d.standard_error[k])) se[kNames[k]] = Finite(d.standard_error[k]);
      if (!d.bound[k].empty()) bound[kNames[k]] = d.bound[k];
    }
    if (!se.empty()) drift["standard_errors"] = se;
    if (!bound.empty()) drift["at_bound"] = bound;
    drift["rmse_half_second_before"] = Finite(d.rmse_before[0]);
    drift["rmse_half_second_after"] = Finite(d.rmse_after[0]);
    drift["rmse_second_before"] = Finite(d.rmse_before[1]);
    drift["rmse_second_after"] = Finite(d.rmse_after[1]);
    drift["rows"] = d.rows;
    drift["held_out_log_score_before"] = Finite(d.held_out_before);
    drift["held_out_log_score_after"] = Finite(d.held_out_after);
    drift["evaluations"] = d.evaluations;
    if (!d.note.empty()) drift["note"] = d.note;
    j["drift"] = drift;
  }
  return j;
}

// One of the drift's numbers: its value, its standard error where it has one, its unit,
// and its bound where it sits on one.
std::string DriftNumber(const OmniDriftIdentification& d, std::size_t k, const char* unit) {
  const double value = k < 3 ? d.drift.sd[k] : d.drift.correlation_time;
  std::string out = Number(value, "%.3g");
  if (!std::isnan(d.standard_error[k])) out += " +- " + Number(d.standard_error[k], "%.2g");
  out += std::string(" ") + unit;
  if (d.bound[k] == "lower") out += " (at its lower bound)";
  if (d.bound[k] == "upper") out += " (at its upper bound)";
  return out;
}

// One sentence on the noise's drift: what was fitted, and kept or why not.
std::string DriftSentence(const OmniDriftIdentification& d) {
  std::string out = std::string(d.kept ? "kept" : "not kept") + ": forward " + DriftNumber(d, 0, "m/s") + ", sideways " +
                    DriftNumber(d, 1, "m/s") + ", turn " + DriftNumber(d, 2, "rad/s") + ", lasting " +
                    DriftNumber(d, 3, "s") + "; predictions 0.5 and 1 s ahead " +
                    Number(1000 * d.rmse_before[0], "%.3g") + " -> " + Number(1000 * d.rmse_after[0], "%.3g") + " and " +
                    Number(1000 * d.rmse_before[1], "%.3g") + " -> " + Number(1000 * d.rmse_after[1], "%.3g") +
                    " mm over " + std::to_string(d.rows) + " rows";
  if (d.held_out_rows > 0)
    out += "; held-out blocks " + Number(d.held_out_before, "%.4g") + " -> " + Number(d.held_out_after, "%.4g") + " nats per row";
  if (!d.note.empty()) out += " (" + d.note + ")";
  return out;
}

ordered_json CalibrationJson(const std::vector<OmniCalibration>& calibration) {
  ordered_json out = ordered_json::array();
  for (const OmniCalibration& c : calibration) {
    out.push_back({{"frames", c.frames},
                   {"seconds", c.seconds},
                   {"rows", c.rows},
                   {"position_50", c.position_50},
                   {"position_90", c.position_90},
                   {"heading_50", c.heading_50},
                   {"heading_90", c.heading_90},
                   {"energy_score", c.energy_score},
                   {"constant_spread_energy_score", c.baseline_energy_score},
                   {"constant_spread", c.baseline_spread},
                   {"energy_gain", c.EnergyGain()},
                   {"log_score", Finite(c.log_score)},
                   {"pit_position", c.position_pit},
                   {"pit_heading", c.heading_pit}});
  }
  return out;
}

// report.json's calibration_by_distance: per range of distances, the calibration per horizon.
ordered_json DistanceCalibrationJson(const std::vector<OmniDistanceCalibration>& by_distance) {
  ordered_json by = ordered_json::array();
  for (const OmniDistanceCalibration& d : by_distance) {
    ordered_json x;
    x["distance_from"] = d.from;
    x["distance_to"] = std::isfinite(d.to) ? ordered_json(d.to) : ordered_json(nullptr);  // null: no upper end
    x["calibration"] = CalibrationJson(d.calibration);
    by.push_back(x);
  }
  return by;
}

// report.json's spread_budget: per horizon the measured error and the predicted spread
// with its parts (m).
nlohmann::json SpreadBudgetJson(const std::vector<OmniSpreadBudget>& budgets) {
  nlohmann::json out = nlohmann::json::array();
  for (const OmniSpreadBudget& b : budgets) {
    nlohmann::json j = {{"frames", b.frames}, {"seconds", b.seconds},     {"rows", b.rows},
                        {"measured", b.measured}, {"predicted", b.predicted}, {"scale", b.scale}};
    for (int p = 0; p < kCovarianceParts; ++p) j[kOmniCovariancePartKeys[p]] = b.parts[static_cast<std::size_t>(p)];
    j["camera"] = b.camera;
    if (b.parameters > 0) j["parameters"] = b.parameters;
    out.push_back(j);
  }
  return out;
}

// report.json's calibration_by_turn_rate: per quarter (slowest first) its range and
// calibration per horizon.
ordered_json TurnRateCalibrationJson(const std::vector<std::array<OmniTurnQuarter, 4>>& by_turn_rate) {
  ordered_json by = ordered_json::array();
  for (std::size_t k = 0; k < 4; ++k) {
    ordered_json from = ordered_json::array(), to = ordered_json::array();
    std::vector<OmniCalibration> calibration;
    for (const std::array<OmniTurnQuarter, 4>& horizon : by_turn_rate) {
      from.push_back(horizon[k].from);
      to.push_back(horizon[k].to);
      calibration.push_back(horizon[k].calibration);
    }
    by.push_back({{"quarter", k + 1}, {"turn_rate_from", from}, {"turn_rate_to", to},
                  {"calibration", CalibrationJson(calibration)}});
  }
  return by;
}

ordered_json SafeguardJson(const OmniIntervalSafeguard& g, double period) {
  ordered_json out;
  out["on"] = g.on;
  out["kept"] = g.AnyKept();
  ordered_json hs = ordered_json::array();
  auto check = [](const std::array<ScaledIntervals, 2>& c) {
    return ordered_json{{"rows", c[0].rows},
                        {"inside_50_before", c[0].inside_50}, {"inside_50_after", c[1].inside_50},
                        {"inside_90_before", c[0].inside_90}, {"inside_90_after", c[1].inside_90},
                        {"log_score_before", Finite(c[0].log_score)}, {"log_score_after", Finite(c[1].log_score)}};
  };
  for (const OmniSafeguardHorizon& h : g.horizons) {
    hs.push_back({{"frames", h.frames},
                  {"seconds", h.frames * period},
                  {"rows", h.rows},
                  {"position_scale", h.position},
                  {"position_growth", h.position_growth},
                  {"position_kept", h.position_kept},
                  {"heading_scale", h.heading},
                  {"heading_growth", h.heading_growth},
                  {"heading_kept", h.heading_kept},
                  {"position_check", check(h.position_check)},
                  {"heading_check", check(h.heading_check)}});
  }
  out["horizons"] = hs;
  if (!g.note.empty()) out["note"] = g.note;
  return out;
}

std::string Verdict(const OmniIdentificationReport& r) {
  const std::vector<OmniGap>& gaps = r.validation.empty() ? r.held_out : r.validation;
  const OmniGap* n = r.Gap(gaps, "nominal model");
  const OmniGap* i = r.Gap(gaps, "identified model");
  const OmniGap* c = r.Gap(gaps, "constant velocity");
  if (!n || !i || !c) return "no held-out rows to score on";
  std::ostringstream s;
  s << "On " << (r.validation.empty() ? "the held-out blocks" : "the validation logs") << ", the " << r.horizon
    << "-frame position error is " << Number(1000 * i->rmse, "%.3g") << " mm identified against " << Number(1000 * n->rmse, "%.3g")
    << " mm nominal and " << Number(1000 * c->rmse, "%.3g") << " mm for constant-velocity extrapolation: the identified model "
    << (i->rmse < c->rmse ? "beats" : "does not beat") << " having no model at all (" << Number(i->rmse / c->rmse, "%.2f")
    << "x).";
  return s.str();
}

// The report's horizons as a table: position RMSE in mm.
HorizonTable TableOf(const OmniIdentificationReport& r) {
  HorizonTable t;
  if (r.horizons.empty()) return t;
  for (const OmniGap& g : r.horizons.front().gaps) t.predictors.push_back(g.name);
  for (const OmniHorizonGaps& h : r.horizons) {
    t.horizons.push_back(h.label);
    t.rows.push_back(h.rows);
    t.mm.emplace_back();
    for (const OmniGap& g : h.gaps) t.mm.back().push_back(1000 * g.rmse);
  }
  return t;
}

SeriesPlot AxisPlot(const OmniIdentificationSeries& s, int axis, bool against_command) {
  static const char* units[3] = {"m/s", "m/s", "rad/s"};
  SeriesPlot plot;
  plot.title = std::string(kOmniAxisNames[axis]) + (against_command ? ": velocity against the command" : ": velocity over the first stretch of the log");
  plot.y_label = std::string(kOmniAxisNames[axis]) + " velocity [" + units[axis] + "]";
  plot.height = 420;
  auto column = [&](const std::vector<std::array<double, 3>>& v) {
    std::vector<double> out;
    for (const auto& x : v) out.push_back(x[static_cast<std::size_t>(axis)]);
    return out;
  };
  if (against_command) {
    plot.x_label = "command [" + std::string(units[axis]) + "]";
    plot.width = 600;
    plot.height = 480;
    PlotSeries m{"measured", column(s.command), column(s.measured), true};
    m.color = 0x999999;
    plot.series.push_back(m);
    plot.series.push_back({"nominal model", column(s.command), column(s.nominal), true});
    plot.series.push_back({"identified model", column(s.command), column(s.identified), true});
  } else {
    PlotSeries m{"measured", s.t, column(s.measured), false};
    m.color = 0x999999;
    plot.series.push_back(m);
    plot.series.push_back({"command", s.t, column(s.command), false});
    plot.series.push_back({"nominal model", s.t, column(s.nominal), false});
    plot.series.push_back({"identified model", s.t, column(s.identified), false});
  }
  return plot;
}

}  // namespace

std::string FormatOmniIdentificationJson(const OmniIdentificationReport& r) {
  ordered_json j;
  j["robot"] = "omni";
  j["model"] = r.model_name;
  j["metric"] = "RMS over held-out frames of the " + std::to_string(r.horizon) +
                "-frame prediction's position error (m); pose_rms adds the heading error at the chassis rim";
  j["verdict"] = Verdict(r);
  j["held_out"] = GapsJson(r.held_out);
  if (!r.validation.empty()) j["validation"] = GapsJson(r.validation);
  if (!r.horizons.empty()) {
    const HorizonTable t = TableOf(r);
    ordered_json hs = ordered_json::array();
    for (std::size_t k = 0; k < r.horizons.size(); ++k) {
      const OmniHorizonGaps& h = r.horizons[k];
      const int best = t.Best(k);
      hs.push_back({{"label", h.label}, {"frames", h.frames}, {"seconds", h.seconds}, {"rows", h.rows},
                    {"best", best < 0 ? std::string() : t.predictors[static_cast<std::size_t>(best)]},
                    {"gaps", GapsJson(h.gaps)}});
    }
    j["horizons_on"] = r.horizons_on;
    j["horizons"] = hs;
  }
  j["driving_noise"] = NoiseJson(r);
  if (!r.calibration.empty()) {
    j["calibration_on"] = r.validation.empty() ? "held-out blocks" : "validation logs";
    j["calibration"] = CalibrationJson(r.calibration);
  }
  if (!r.calibration_by_distance.empty()) j["calibration_by_distance"] = DistanceCalibrationJson(r.calibration_by_distance);
  if (!r.calibration_by_turn_rate.empty()) j["calibration_by_turn_rate"] = TurnRateCalibrationJson(r.calibration_by_turn_rate);
  if (!r.spread_budget.empty()) {
    j["spread_budget_on"] = r.spread_budget_on;
    j["spread_budget"] = SpreadBudgetJson(r.spread_budget);
  }
  if (!r.safeguard.on.empty()) j["intervals_safeguard"] = SafeguardJson(r.safeguard, r.frame_period);
  j["noise_floor"] = r.noise_floor;
  j["collinearity_index"] = Finite(r.collinearity);
  j["fit_rms_nominal"] = r.fit_cost_nominal;
  j["fit_rms_identified"] = r.fit_cost_identified;
  ordered_json params = ordered_json::array();
  for (const IdentifiedParameter& p : r.parameters) {
    ordered_json x;
    x["name"] = p.name;
    x["key"] = p.key;
    x["unit"] = p.unit;
    x["nominal"] = p.nominal;
    x["value"] = p.value;
    x["standard_error"] = Finite(p.standard_error);
    x["estimated"] = p.estimated;
    x["held"] = p.held;
    x["meaning"] = p.meaning;
    if (!p.note.empty()) x["note"] = p.note;
    params.push_back(x);
  }
  j["parameters"] = params;
  ordered_json profile = ordered_json::array();
  for (std::size_t k = 0; k < r.delay_profile_s.size(); ++k) {
    profile.push_back({{"delay", r.delay_profile_s[k]}, {"fit_rms", Finite(r.delay_profile_rms[k])}});
  }
  j["delay_profile"] = profile;
  j["backend"] = r.backend;
  j["horizon"] = r.horizon;
  j["frame_period"] = r.frame_period;
  j["block_seconds"] = r.block_seconds;
  j["held_out_share"] = r.held_out_share;
  j["fit_rows"] = r.fit_rows;
  j["held_out_rows"] = r.held_out_rows;
  j["logs"] = r.logs;
  j["validation_logs"] = r.validation_logs;
  j["solver_iterations"] = r.solver_iterations;
  j["replays"] = r.evaluations;
  j["notes"] = r.notes;
  return j.dump(2) + "\n";
}

std::string FormatOmniIdentificationTable(const OmniIdentificationReport& r) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line, "%-38s %12s %12s %12s  %s\n", "parameter", "nominal", "identified", "std. error", "unit");
  s << line;
  for (const IdentifiedParameter& p : r.parameters) {
    // The note after the columns, whole (a note is longer than any fixed buffer).
    std::snprintf(line, sizeof line, "%-38s %12s %12s %12s  %s", p.name.c_str(), Number(p.nominal).c_str(),
                  p.estimated ? Number(p.value).c_str() : "-", p.estimated ? Number(p.standard_error, "%.2g").c_str() : "",
                  p.unit.c_str());
    s << line << ((p.estimated && !p.held) || p.note.empty() ? "" : "  (" + p.note + ")") << "\n";
  }
  auto table = [&](const char* title, const std::vector<OmniGap>& gaps) {
    if (gaps.empty()) return;
    s << title << ", " << r.horizon << "-frame prediction error:\n";
    std::snprintf(line, sizeof line, "  %-20s %14s %12s %12s %12s\n", "", "position [mm]", "forward", "sideways",
                  "turn (rim)");
    s << line;
    for (const OmniGap& g : gaps) {
      std::snprintf(line, sizeof line, "  %-20s %14.2f %12.2f %12.2f %12.2f\n", g.name.c_str(), 1000 * g.rmse,
                    1000 * g.forward, 1000 * g.sideways, 1000 * g.turn);
      s << line;
    }
  };
  table("held-out blocks", r.held_out);
  table("validation logs", r.validation);
  if (!r.horizons.empty()) {
    s << "every horizon (" << r.horizons_on << "), position error [mm], * best:\n" << FormatHorizonTable(TableOf(r));
  }
  if (r.noise_identified) {
    s << "driving noise for predictions ahead (" << (r.noise.kept ? "kept" : "not kept") << "; start -> identified):\n";
    for (const OmniNoiseParameter& p : r.noise.parameters) {
      std::snprintf(line, sizeof line, "  %-22s %12s -> %12s +- %-10s %s", p.name.c_str(), Number(p.start).c_str(),
                    Number(p.value).c_str(), Number(p.standard_error, "%.2g").c_str(), p.unit.c_str());
      s << line << NoiseBoundNote(p);
      // The search moves the process noise by a factor on what the response's fit left.
      if (p.name == "process_noise_scale")
        s << "  (a factor on the 4-frame fit's; the table's process_noise.scale is the product)";
      s << "\n";
    }
  }
  if (r.drift_identified)
    s << "the noise's drift (a slow slip the observer learns and carries ahead; fitted on " << r.drift.on
      << "): " << DriftSentence(r.drift) << "\n";
  if (!r.calibration.empty()) {
    s << "calibration of the predictions ("
      << CalibratedOn(r)
      << "; energy score against a constant spread):\n"
      << FormatCalibrationTable(r.calibration);
  }
  if (!r.calibration_by_distance.empty()) {
    s << "the same by how far the predictions' inputs lie from the fit blocks' (observer.seen_inputs; 1 is a "
         "typical command's size; each range's constant spread fitted on its rows):\n"
      << FormatDistanceCalibrationTables(r.calibration_by_distance);
  }
  if (!r.calibration_by_turn_rate.empty()) {
    s << "the same by quarter of the turn rate over each prediction (rad/s: position 50 / 90 % ellipses hold):\n"
      << FormatTurnRateCalibrationTable(r.calibration_by_turn_rate);
  }
  if (!r.spread_budget.empty()) {
    s << "where the predicted position spread comes from on the " << r.spread_budget_on
      << " (RMS, mm; the parts add in squares to the filter's spread; measured / predicted near 1 when calibrated):\n"
      << FormatSpreadBudgets(r.spread_budget);
  }
  if (!r.safeguard.on.empty()) {
    s << "intervals' safeguard (a conformal scale of the predicted covariance, fitted on the " << r.safeguard.on
      << "; each fold with the others' scale, its share in the 90 % regions without -> with it):\n"
      << FormatSafeguard(r.safeguard, r.frame_period);
  }
  s << Verdict(r) << "\n";
  for (const auto& n : r.notes) s << "note: " << n << "\n";
  return s.str();
}

std::string FormatOmniIdentificationHtml(const OmniIdentificationReport& r, Renderer& renderer) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Identification: " << HtmlEscape(r.model_name)
    << "</title>\n<style>body{font-family:sans-serif;max-width:1250px;margin:2em auto;color:#222}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:left}"
       "th{background:#eee}.verdict{font-size:1.25em;padding:.7em;border-left:6px solid #0072B2;background:#f3f8fc}"
       ".small{color:#666;font-size:.9em}td.n{text-align:right}</style></head><body>\n";
  h << "<h1>Identification of " << HtmlEscape(r.model_name) << " (omni)</h1>\n";
  h << "<p class=\"verdict\">" << HtmlEscape(Verdict(r)) << "</p>\n";
  h << "<p>Fitted on " << r.fit_rows << " predictions from the fit blocks; scored on " << r.held_out_rows
    << " held-out rows (" << Number(100 * r.held_out_share, "%.0f") << " % of the " << Number(r.block_seconds, "%.3g")
    << " s blocks, which no fit saw). Engine: " << HtmlEscape(r.backend) << ". Logs:";
  for (const auto& l : r.logs) h << " <code>" << HtmlEscape(l) << "</code>";
  for (const auto& l : r.validation_logs) h << " <code>" << HtmlEscape(l) << "</code> (validation)";
  h << "</p>\n";
  auto gap_table = [&](const char* title, const std::vector<OmniGap>& gaps) {
    if (gaps.empty()) return;
    h << "<h2>" << title << "</h2>\n<table><tr><th>predictor</th><th>position RMSE [mm]</th><th>forward [mm]</th>"
         "<th>sideways [mm]</th><th>turn at the rim [mm]</th></tr>\n";
    for (const OmniGap& g : gaps) {
      h << "<tr><td>" << HtmlEscape(g.name) << "</td><td class=n>" << Number(1000 * g.rmse, "%.2f") << "</td><td class=n>"
        << Number(1000 * g.forward, "%.2f") << "</td><td class=n>" << Number(1000 * g.sideways, "%.2f") << "</td><td class=n>"
        << Number(1000 * g.turn, "%.2f") << "</td></tr>\n";
    }
    h << "</table>\n";
  };
  gap_table("Held-out blocks", r.held_out);
  gap_table("Validation logs", r.validation);
  if (!r.horizons.empty()) {
    h << "<h2>Every horizon</h2>\n<p>Position RMSE [mm] on the " << HtmlEscape(r.horizons_on)
      << " at each horizon, every predictor on the same rows (whose prediction ends there; it starts from the state "
         "estimated from the measurements up to its start, and runs free on the logged commands). Best in bold.</p>\n"
      << FormatHorizonTableHtml(TableOf(r));
  }
  h << "<p class=\"small\">Noise floor from the camera (third differences of consecutive measured frames): "
    << Number(1000 * r.noise_floor, "%.2f") << " mm (pose metric).</p>\n";

  h << "<h2>Parameters</h2>\n<p class=\"small\">Collinearity index of the parameters with a standard error: "
    << Number(r.collinearity, "%.3g")
    << " (1: their effects independent; a parameter that would take it above 20 is held at the fit's value, its note "
       "naming what it trades with).</p>\n<table><tr><th>parameter</th><th>model file</th><th>nominal</th><th>identified</th>"
       "<th>std. error</th><th>unit</th><th>meaning</th></tr>\n";
  for (const IdentifiedParameter& p : r.parameters) {
    h << "<tr><td>" << HtmlEscape(p.name) << "</td><td><code>" << HtmlEscape(p.key) << "</code></td><td class=n>"
      << Number(p.nominal) << "</td><td class=n>" << (p.estimated ? Number(p.value) : "-") << "</td><td class=n>"
      << (p.estimated ? Number(p.standard_error, "%.2g") : "") << "</td><td>" << HtmlEscape(p.unit) << "</td><td>"
      << HtmlEscape(p.meaning) << (p.note.empty() ? "" : " <i>(" + HtmlEscape(p.note) + ")</i>") << "</td></tr>\n";
  }
  h << "</table>\n";

  if (r.noise_identified) {
    h << "<h2>Driving noise</h2>\n<p>How far and how long the robot wanders from what its wheels do, with the "
         "camera's noise and the model's process noise: identified by the likelihood of the predictions 4, 16 and 63 "
         "frames ahead on the held-out blocks (rows the response was not fitted on), "
      << (r.noise.kept ? "kept: fitted on each half of those blocks, it scores the other half better than the "
                         "prediction-error fit's noise (log score "
                       : "not kept: fitted on each half of those blocks, it scores the other half worse than the "
                         "prediction-error fit's noise (log score ")
      << Number(r.noise.held_out_before) << " &rarr; " << Number(r.noise.held_out_after)
      << " nats per row). The identified model draws its noise in <code>run</code> and <code>serve</code> "
         "(<code>driving_noise.simulated</code>; <code>--driving-noise off</code> turns it off)."
      << "</p>\n<table><tr><th>parameter</th><th>start</th><th>identified</th><th>std. error</th><th>unit</th></tr>\n";
    for (const OmniNoiseParameter& p : r.noise.parameters) {
      h << "<tr><td>" << HtmlEscape(p.name) << "</td><td class=n>" << Number(p.start) << "</td><td class=n>"
        << Number(p.value) << "</td><td class=n>" << Number(p.standard_error, "%.2g") << "</td><td>"
        << HtmlEscape(p.unit + NoiseBoundNote(p)) << "</td></tr>\n";
    }
    h << "</table>\n";
    if (!r.noise.growth_note.empty()) h << "<p class=\"small\">" << HtmlEscape(r.noise.growth_note) << "</p>\n";
    if (r.drift_identified)
      h << "<p>The noise's drift, a slow slip beside it that the observer learns over the frames and carries into "
           "every prediction (a run's own drift; fitted on "
        << HtmlEscape(r.drift.on) << ", kept where it takes 5 % off them and the rows it was not fitted on are no worse): "
        << HtmlEscape(DriftSentence(r.drift)) << ".</p>\n";
  }
  if (!r.calibration.empty()) {
    h << "<h2>Calibration</h2>\n<p>The identified model's predictive distribution on the "
      << CalibratedOn(r)
      << ": the share of measured positions inside its central 50 % and 90 % ellipses (and of headings inside the "
         "intervals), which a calibrated model holds at 50 % and 90 %; the energy score of the position beside the "
         "same mean with one round spread per horizon (fitted on the fit blocks), lower is better.</p>\n"
      << FormatCalibrationHtml(r.calibration, renderer);
  }
  if (!r.calibration_by_distance.empty()) {
    h << "<p>The same by how far the predictions' inputs lie from those of the fit blocks (1 is a typical command's "
         "size): where the intervals can be relied on.</p>\n<pre>"
      << HtmlEscape(FormatDistanceCalibrationTables(r.calibration_by_distance)) << "</pre>\n";
  }
  if (!r.calibration_by_turn_rate.empty()) {
    h << "<p>The same by quarter of the turn rate over each prediction (rad/s; slowest first): whether the "
         "intervals hold in the fastest turns as on average.</p>\n<pre>"
      << HtmlEscape(FormatTurnRateCalibrationTable(r.calibration_by_turn_rate)) << "</pre>\n";
  }
  if (!r.spread_budget.empty()) {
    h << "<p>Where the predicted position spread comes from on the " << HtmlEscape(r.spread_budget_on)
      << ": the start estimate carried on, "
         "the process noise, the driving noise, the drift, the camera and, on validation logs, the parameters' own "
         "uncertainty (RMS, mm; they add in squares), beside the measured error.</p>\n<pre>"
      << HtmlEscape(FormatSpreadBudgets(r.spread_budget)) << "</pre>\n";
  }
  if (!r.safeguard.on.empty()) {
    h << "<h3>The intervals' safeguard</h3>\n<p>A conformal scale of the predicted covariance per horizon, fitted on "
      << HtmlEscape(r.safeguard.on)
      << " (docs/identification.md): the scale that makes the 90 % regions hold 90 % of those rows, kept where they "
         "were off by more than two standard errors and each fold, with the scale of the others, comes nearer 90 % "
         "without a worse log density. Each fold's share in the 90 % regions without and with it:</p>\n<pre>"
      << HtmlEscape(FormatSafeguard(r.safeguard, r.frame_period)) << "</pre>\n";
  }
  if (!r.delay_profile_s.empty()) {
    SeriesPlot plot;
    plot.title = "Fit error against the total delay (model's response, before the fit)";
    plot.x_label = "total delay [ms]";
    plot.y_label = "fit RMS [m]";
    plot.height = 380;
    std::vector<double> ms, rms;
    for (std::size_t k = 0; k < r.delay_profile_s.size(); ++k) {
      if (!std::isfinite(r.delay_profile_rms[k])) continue;
      ms.push_back(1000 * r.delay_profile_s[k]);
      rms.push_back(r.delay_profile_rms[k]);
    }
    plot.series.push_back({"fit error", ms, rms, false});
    h << HtmlImage(RenderSeriesPlot(plot, renderer), "delay profile") << "\n";
  }
  for (const OmniIdentificationSeries& s : r.series) {
    if (s.t.empty()) continue;
    h << "<h2>Measured against nominal and identified, per axis</h2>\n<p>Body velocity over the first stretch of <code>"
      << HtmlEscape(s.log) << "</code>: measured (central differences of the poses), the command sent the identified "
      << "delay earlier, and each model's one-frame prediction from the measured state.</p>\n";
    for (int axis = 0; axis < 3; ++axis) {
      h << HtmlImage(RenderSeriesPlot(AxisPlot(s, axis, false), renderer), "velocity over time") << "<br>\n";
      h << HtmlImage(RenderSeriesPlot(AxisPlot(s, axis, true), renderer), "velocity against command") << "<br>\n";
    }
  }
  if (!r.notes.empty()) {
    h << "<h2>Notes</h2><ul>\n";
    for (const auto& n : r.notes) h << "<li>" << HtmlEscape(n) << "</li>\n";
    h << "</ul>\n";
  }
  h << "<p class=\"small\">twinsim identify; method: docs/identification.md, \"The omni robot\". " << r.solver_iterations
    << " solver iterations, " << r.evaluations << " replays of the fit blocks.</p>\n"
    << "</body></html>\n";
  return h.str();
}

}  // namespace twinsim
