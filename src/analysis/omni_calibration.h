// How well an omni model's predictive distribution matches where the robot was measured
// (identify's and compare's calibration; docs/identification.md, "Calibration").
//
// A prediction K frames ahead from the observer (analysis/omni_replay.h with
// `covariance`) is a Gaussian over the pose: the predicted mean and the filter's
// covariance, to which the camera's own noise is added, since what is scored is the
// measured pose. Over rows with a measurement it is scored as a forecaster is:
//   - coverage: the share of measured positions inside the central 50 % and 90 %
//     ellipses (Mahalanobis distance d^2 <= -2 ln(1 - p) for two dimensions), and of
//     headings inside the central intervals; a calibrated model holds 50 % and 90 %;
//   - the PIT (probability integral transform): 1 - exp(-d^2 / 2) for the position,
//     Phi(z) for the heading; uniform on [0, 1] when calibrated (a U: too narrow, a hump:
//     too wide), shown as a histogram;
//   - the energy score of the position, E||X - y|| - E||X - X'|| / 2 (Gneiting and
//     Raftery 2007), m, lower is better: it rewards a spread that is right row by row,
//     beside the baseline of the same mean with one round spread per horizon, the one
//     that scores best on the rows it is fitted on (a model's distribution must beat
//     that to be worth its noise model);
//   - the mean negative log density (nats), what the noise's identification minimises.
// Where the covariance was estimated from sampled rollouts (the learned backend), the
// coverage, the PIT and the log density are those of the Student t that the estimate
// implies (PredictiveError below); the energy score keeps the Gaussian of its covariance.
// The expectations of the energy score are taken over a fixed set of draws, so scores
// are deterministic.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <functional>
#include <limits>
#include <vector>

#include "analysis/omni_replay.h"
#include "analysis/omni_spread_budget.h"
#include "robots/omni/omni_log.h"

namespace twinsim {

// One predicted row: the measured pose minus the mean and the distribution's covariance.
//
// The observer's prediction is Gaussian with a known covariance. The learned backend's
// covariance is estimated from n sampled rollouts about the prediction (their mean
// square, n S ~ Wishart(Sigma, n)): the measured pose's distribution given S is then
// Student's t, not N(0, S) (the posterior predictive; in p dimensions t with n - p + 1
// degrees of freedom and scale n S / (n - p + 1)): e' S^-1 e (n - p + 1) / (p n) is
// F(p, n - p + 1) distributed. Scored as a Gaussian, 16 draws make the 50 % ellipse hold
// 46 % and the 90 % one 85 %, and a noise fitted by the Gaussian log density comes out
// a third too wide in variance (n / (n - p - 1)) to make up for it. With the camera's
// known covariance added, the degrees of freedom are those of the sum (Satterthwaite:
// n (|S + C| / |S|)^(2/p)).
struct PredictiveError {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();  // x, y in the field frame (m); theta (rad)
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();  // its covariance: the prediction's plus the camera's
  int draws = 0;                                // 0: c is known; else the prediction's part was estimated from this many draws
  Eigen::Matrix3d drawn = Eigen::Matrix3d::Zero();  // that part (c minus the camera's)
  double input_distance = 0;  // the prediction's mean distance from the model's seen inputs (0: none)
  double turn_rate = 0;       // rad/s: the log's mean turn rate over the prediction's frames (MeasuredTurnRate)
};

// The mean of |turn rate| (rad/s) the log's poses show over the `frames` frames before
// row i: the sum of each row's |heading change| from the row before (a row without a
// measurement has its interpolated pose), over the time they span; 0 at the log's start.
// A robot that turns back and forth reads its speed of turning, not its net turn.
double MeasuredTurnRate(const OmniLog& log, std::size_t i, int frames);

// The part of a pose a row's covariance is taken over.
enum class PosePart { kPosition, kHeading, kPose };
// The degrees of freedom behind a row's covariance over `part`: the draws, grown where
// the camera's known part dominates; infinity for a known covariance.
double EffectiveDraws(const PredictiveError& row, PosePart part);

// A row's probability integral transforms: the position's (the share of its
// distribution nearer the mean, in Mahalanobis distance, than the measured position) and
// the heading's (its distribution function at the measured heading); chi-square and
// normal for a known covariance, F and Student's t for one estimated from draws. The
// row lies inside the central p region of the position where `position` <= p, of the
// heading where |2 heading - 1| <= p.
struct Pits {
  double position = 0, heading = 0;
};
Pits PitsOf(const PredictiveError& row);

// Row i of a replay run with `covariance` (predicted, with a measurement).
PredictiveError PredictiveErrorAt(const OmniLog& log, const OmniReplayResult& result, std::size_t i);
// The rows of a replay run with `covariance` that were predicted, hold a measurement and
// that `keep` accepts (all when empty); with `frames` (the horizon predicted), each with
// its MeasuredTurnRate over them.
std::vector<PredictiveError> PredictiveErrors(const OmniLog& log, const OmniReplayResult& result,
                                              const std::function<bool(std::size_t)>& keep = {}, int frames = 0);

inline constexpr int kPitBins = 10;

// The scores at one horizon.
struct OmniCalibration {
  int frames = 0;      // K
  double seconds = 0;  // K frame periods
  int rows = 0;        // rows scored
  double position_50 = 0, position_90 = 0;  // shares inside the central ellipses
  double heading_50 = 0, heading_90 = 0;    // shares inside the central intervals
  double energy_score = 0;           // m, mean over the rows
  double baseline_energy_score = 0;  // m, the same mean under the constant spread
  double baseline_spread = 0;        // m, the constant spread per coordinate
  double log_score = 0;              // nats per row, mean negative log density of the pose
  std::array<int, kPitBins> position_pit{};  // counts per tenth of [0, 1]
  std::array<int, kPitBins> heading_pit{};
  // How much the model's energy score improves on the baseline's: 1 - ES / ES_baseline.
  double EnergyGain() const;
};

// The constant spread s (m) whose round Gaussian N(mean, s^2 I) has the lowest mean
// energy score over `rows` (a golden-section search); 0 without rows.
double ConstantSpread(const std::vector<PredictiveError>& rows);

// Scores `rows` at one horizon, the baseline with `constant_spread` (from other rows).
OmniCalibration Calibrate(const std::vector<PredictiveError>& rows, double constant_spread);

// The calibration of `model` on `backend` (a physics one: the observer's) over a whole
// log at each of `horizons` (frames; 4, 16 and 63 by default), predicting from every
// `stride`-th frame after the observer's warm-up (`compare`). The constant spread is
// fitted on the same rows: a baseline with hindsight, so a model that beats it beats any
// constant spread. A horizon the log is too short for has no rows. Throws as ReplayOmniLog.
std::vector<OmniCalibration> CalibrateOmniLog(const OmniModel& model, const OmniLog& log, const std::string& backend,
                                              std::vector<int> horizons = {4, 16, 63}, int stride = 2);

// Scores rows[h], predicted horizons[h] frames ahead (frames of `frame_period` s), whose
// prediction's mean distance from the model's seen inputs (PredictiveError::
// input_distance; 0 for a model without them) lies in [from, to), each horizon's
// baseline fitted on those rows.
std::vector<OmniCalibration> CalibrateRows(const std::vector<std::vector<PredictiveError>>& rows,
                                           const std::vector<int>& horizons, double frame_period, double from = 0,
                                           double to = std::numeric_limits<double>::infinity());
// The distances `compare` and `identify` split a calibration at: within the fit's reach,
// near it, beyond (robots/omni/omni_seen_inputs.h: 1 is a typical command's size).
inline constexpr std::array<double, 4> kCalibrationDistances{0, 0.25, 1, std::numeric_limits<double>::infinity()};

// A calibration of the rows whose inputs lie in [from, to) of the fit's.
struct OmniDistanceCalibration {
  double from = 0, to = 0;
  std::vector<OmniCalibration> calibration;  // per horizon
};

// CalibrateRows over each range of kCalibrationDistances.
std::vector<OmniDistanceCalibration> CalibrateRowsByDistance(const std::vector<std::vector<PredictiveError>>& rows,
                                                             const std::vector<int>& horizons, double frame_period);

// A calibration of the rows whose measured turn rate (PredictiveError::turn_rate) lies in
// [from, to] rad/s (its slowest and fastest row): a quarter of one horizon's rows.
struct OmniTurnQuarter {
  double from = 0, to = 0;
  OmniCalibration calibration;
};

// Each horizon's rows in four quarters of their measured turn rate, slowest first (by
// rank among that horizon's rows, so the quarters hold as many rows each, give or take
// one), each quarter's baseline
// fitted on its rows: whether the intervals hold in the fastest turns as they do on
// average (issue 64). One array per horizon; a horizon without rows has empty quarters.
std::vector<std::array<OmniTurnQuarter, 4>> CalibrateRowsByTurnRate(const std::vector<std::vector<PredictiveError>>& rows,
                                                                    const std::vector<int>& horizons, double frame_period);

// The rows of a whole log predicted by `model` on `backend` at each of `horizons` (sorted
// increasing) from every `stride`-th frame counted from the log's first (the same rows
// for every model), with their covariances: one list per horizon, all empty where the
// log is too short for the longest. With `budgets`, each horizon's spread budget of the
// same rows into it (analysis/omni_spread_budget.h). With `parameter_shifts`, the
// parameters' own uncertainty in every covariance (OmniReplayOptions::parameter_shifts,
// replayed on the engine the model was fitted on, else the analytic). Throws as
// ReplayOmniLog.
std::vector<std::vector<PredictiveError>> OmniLogPredictiveErrors(
    const OmniModel& model, const OmniLog& log, const std::string& backend, const std::vector<int>& horizons, int stride,
    std::vector<OmniSpreadBudget>* budgets = nullptr,
    const std::vector<std::array<OmniModel, 2>>& parameter_shifts = {});

// The negative log density (nats) of one row's pose under its distribution (its Gaussian,
// or the Student t of a covariance estimated from draws); infinity for a covariance that
// is not positive definite.
double LogScore(const PredictiveError& row);
// The same of one part of the pose (the position's two coordinates, the heading, or the
// pose: LogScore), its own degrees of freedom (EffectiveDraws).
double PartLogScore(const PredictiveError& row, PosePart part);
// Its mean over `rows` (0 without rows): the cost the driving noise is identified by.
double MeanLogScore(const std::vector<PredictiveError>& rows);

}  // namespace twinsim
