#include "analysis/omni_calibration_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "io/html_text.h"
#include "io/printf_number.h"

namespace twinsim {

namespace {

std::string Percent(double share) { return PrintfNumber("%.1f", 100 * share); }
std::string Millimetres(double m) { return PrintfNumber("%.2f", 1000 * m); }

std::string HorizonLabel(const OmniCalibration& c) {
  char s[64];
  std::snprintf(s, sizeof s, "%d frames (%.2f s)", c.frames, c.seconds);
  return s;
}

}  // namespace

std::string CalibrationDistanceRange(double from, double to) {
  return std::isfinite(to) ? PrintfNumber("%g", from) + " to " + PrintfNumber("%g", to) : "beyond " + PrintfNumber("%g", from);
}

std::string FormatDistanceCalibrationTables(const std::vector<OmniDistanceCalibration>& by_distance) {
  std::ostringstream s;
  for (const OmniDistanceCalibration& d : by_distance) {
    if (std::none_of(d.calibration.begin(), d.calibration.end(), [](const OmniCalibration& c) { return c.rows > 0; }))
      continue;
    s << " inputs " << CalibrationDistanceRange(d.from, d.to) << " from the fit's:\n" << FormatCalibrationTable(d.calibration);
  }
  return s.str();
}

std::string FormatCalibrationTable(const std::vector<OmniCalibration>& calibration) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line, "  %-20s %6s %8s %8s %8s %8s %12s %12s %7s\n", "horizon", "rows", "pos 50%", "pos 90%",
                "head 50%", "head 90%", "energy [mm]", "const. [mm]", "gain");
  s << line;
  for (const OmniCalibration& c : calibration) {
    if (c.rows == 0) {
      std::snprintf(line, sizeof line, "  %-20s %6d  (no rows)\n", HorizonLabel(c).c_str(), c.rows);
    } else {
      std::snprintf(line, sizeof line, "  %-20s %6d %8s %8s %8s %8s %12s %12s %6.1f%%\n", HorizonLabel(c).c_str(), c.rows,
                    Percent(c.position_50).c_str(), Percent(c.position_90).c_str(), Percent(c.heading_50).c_str(),
                    Percent(c.heading_90).c_str(), Millimetres(c.energy_score).c_str(),
                    Millimetres(c.baseline_energy_score).c_str(), 100 * c.EnergyGain());
    }
    s << line;
  }
  return s.str();
}

std::string FormatTurnRateCalibrationTable(const std::vector<std::array<OmniTurnQuarter, 4>>& by_turn_rate) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line, "  %-20s %-26s %-26s %-26s %-26s\n", "horizon", "slowest quarter", "second",
                "third", "fastest quarter");
  s << line;
  for (const std::array<OmniTurnQuarter, 4>& quarters : by_turn_rate) {
    std::snprintf(line, sizeof line, "  %-20s", HorizonLabel(quarters[0].calibration).c_str());
    s << line;
    for (const OmniTurnQuarter& q : quarters) {
      const OmniCalibration& c = q.calibration;
      const std::string cell = c.rows == 0 ? "(no rows)"
                                           : PrintfNumber("%.2f", q.from) + "-" + PrintfNumber("%.2f", q.to) + ": " +
                                                 Percent(c.position_50) + " / " + Percent(c.position_90) + " %";
      std::snprintf(line, sizeof line, " %-26s", cell.c_str());
      s << line;
    }
    s << "\n";
  }
  return s.str();
}

SeriesPlot PitPlot(const std::vector<OmniCalibration>& calibration, bool heading) {
  SeriesPlot plot;
  plot.title = heading ? "PIT of the heading (flat at 1: calibrated; U: too narrow; hump: too wide)"
                       : "PIT of the position (flat at 1: calibrated; U: too narrow; hump: too wide)";
  plot.x_label = "probability integral transform";
  plot.y_label = "density";
  plot.height = 420;
  double top = 2;
  for (const OmniCalibration& c : calibration) {
    if (c.rows == 0) continue;
    PlotSeries s;
    s.name = HorizonLabel(c);
    const auto& counts = heading ? c.heading_pit : c.position_pit;
    for (int b = 0; b < kPitBins; ++b) {
      const double density = counts[static_cast<std::size_t>(b)] * static_cast<double>(kPitBins) / c.rows;
      top = std::max(top, 1.1 * density);
      s.x.push_back(static_cast<double>(b) / kPitBins);
      s.y.push_back(density);
      s.x.push_back(static_cast<double>(b + 1) / kPitBins);
      s.y.push_back(density);
    }
    plot.series.push_back(s);
  }
  plot.series.push_back({"calibrated", {0, 1}, {1, 1}, false, 0x888888});
  plot.range = WorldRect{0, 1, 0, top};
  return plot;
}

std::string FormatCalibrationHtml(const std::vector<OmniCalibration>& calibration, Renderer& renderer) {
  std::ostringstream h;
  h << "<table><tr><th>horizon</th><th>rows</th><th>position in 50 % ellipse</th><th>in 90 %</th>"
       "<th>heading in 50 % interval</th><th>in 90 %</th><th>energy score [mm]</th><th>constant spread's [mm]</th>"
       "<th>gain</th></tr>\n";
  for (const OmniCalibration& c : calibration) {
    h << "<tr><td>" << HtmlEscape(HorizonLabel(c)) << "</td><td class=n>" << c.rows << "</td>";
    if (c.rows == 0) {
      h << "<td colspan=7>no rows</td></tr>\n";
      continue;
    }
    h << "<td class=n>" << Percent(c.position_50) << " %</td><td class=n>" << Percent(c.position_90)
      << " %</td><td class=n>" << Percent(c.heading_50) << " %</td><td class=n>" << Percent(c.heading_90)
      << " %</td><td class=n>" << Millimetres(c.energy_score) << "</td><td class=n>"
      << Millimetres(c.baseline_energy_score) << " (spread " << Millimetres(c.baseline_spread) << ")</td><td class=n>"
      << Percent(c.EnergyGain()) << " %</td></tr>\n";
  }
  h << "</table>\n";
  bool any = false;
  for (const OmniCalibration& c : calibration) any = any || c.rows > 0;
  if (any) {
    h << HtmlImage(RenderSeriesPlot(PitPlot(calibration, false), renderer), "PIT histogram of the position") << "<br>\n";
    h << HtmlImage(RenderSeriesPlot(PitPlot(calibration, true), renderer), "PIT histogram of the heading") << "\n";
  }
  return h.str();
}

}  // namespace twinsim
