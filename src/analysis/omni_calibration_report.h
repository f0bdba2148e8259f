// The calibration of an omni model's predictive distribution (analysis/omni_calibration.h)
// as people read it: a table for the terminal, and for a report an HTML table with the
// PIT histograms (identify's and compare's reports; docs/identification.md, "Calibration").
#pragma once

#include <array>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "render/plot.h"

namespace twinsim {

// One line per horizon: rows, coverage of the 50 % and 90 % position ellipses and
// heading intervals (%), the energy score against the constant spread's (mm) and the gain.
std::string FormatCalibrationTable(const std::vector<OmniCalibration>& calibration);

// The same as an HTML <table>, then the PIT histograms of the position and the heading
// (one line per horizon over the uniform a calibrated model gives).
std::string FormatCalibrationHtml(const std::vector<OmniCalibration>& calibration, Renderer& renderer);

// "0 to 0.25", "beyond 1": a range of distances from the fit's inputs.
std::string CalibrationDistanceRange(double from, double to);

// One table per range that has rows (FormatCalibrationTable), each under a line that
// says how far the predictions' inputs lie from those the fit saw.
std::string FormatDistanceCalibrationTables(const std::vector<OmniDistanceCalibration>& by_distance);

// One line per horizon, one cell per quarter of the measured turn rate (slowest first):
// the quarter's range in rad/s and the shares its 50 % and 90 % position ellipses hold.
std::string FormatTurnRateCalibrationTable(const std::vector<std::array<OmniTurnQuarter, 4>>& by_turn_rate);

// The PIT histograms as a plot: density per tenth of [0, 1], one step line per horizon.
SeriesPlot PitPlot(const std::vector<OmniCalibration>& calibration, bool heading);

}  // namespace twinsim
