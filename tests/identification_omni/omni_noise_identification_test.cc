// The driving noise identified from logs and its predictive distribution scored on a
// validation log (identification_omni/omni_noise_identification.h, analysis/omni_calibration.h),
// on wandering plants (tests/estimation/wandering_plant.h): robots written apart from
// twinsim's models (a first-order lag per axis, no PID, no wheels), whose driving noise
// is a Gauss-Markov disturbance of a size and correlation time drawn off any grid.
// Identification starts from models/omni4.yaml and is never told the noise.
#include "identification_omni/omni_noise_identification.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/omni_calibration_report.h"
#include "analysis/pooled_calibration.h"
#include "diagnosis/diagnosis_plants.h"
#include "identification_omni/omni_identification.h"
#include "estimation/wandering_plant.h"
#include "io/printf_number.h"
#include "test_util.h"

namespace twinsim {
namespace {

testing::WanderingPlant OffGridPlant() {
  testing::WanderingPlant plant;
  plant.noise_sd = {0.137, 0.093, 0.71};
  plant.noise_correlation = 0.23;
  return plant;
}

const OmniNoiseParameter& Parameter(const OmniIdentificationReport& r, const std::string& name) {
  for (const OmniNoiseParameter& p : r.noise.parameters)
    if (p.name == name) return p;
  throw std::logic_error("no parameter " + name);
}

struct NoiseRun {
  OmniIdentificationReport report;
  OmniModel model;
};

// Identified on a minute of the robot per seed, calibrated on another minute (seed 58).
NoiseRun Identify(const testing::WanderingPlant& plant, const std::vector<std::uint64_t>& fit_seeds) {
  NoiseRun run;
  std::vector<OmniLog> fit;
  for (std::uint64_t seed : fit_seeds) fit.push_back(testing::RecordWanderingPlant(plant, 60, seed).log);
  const OmniLog validation = testing::RecordWanderingPlant(plant, 60, 58).log;
  run.report = IdentifyOmni(testing::Omni4(), fit, {validation}, OmniIdentificationOptions{}, &run.model);
  return run;
}

// Identified on the minute drawn with `fit_seed`.
NoiseRun Identify(const testing::WanderingPlant& plant, std::uint64_t fit_seed = 57) {
  return Identify(plant, std::vector<std::uint64_t>{fit_seed});
}

// The standard errors identify reports for the noise, as JSON for
// scripts/noise-calibration-table (null where the blocks do not determine one).
std::string StandardErrorsJson(const OmniIdentificationReport& r) {
  std::string out;
  for (const OmniNoiseParameter& p : r.noise.parameters) {
    out += (out.empty() ? "{\"" : ", \"") + p.name +
           "\": " + (std::isfinite(p.standard_error) ? PrintfNumber("%.4g", p.standard_error) : std::string("null"));
  }
  return out + "}";
}

// The identified model's calibration pooled over eight unseen minutes (the validation
// log and seven more; tests/analysis/pooled_calibration.h says why one is not enough), recorded
// for scripts/noise-calibration-table under `name`.
// With `by_turn_rate`, their rows pooled and split by quarter of the turn rate.
std::vector<testing::PooledCalibration> CalibrateOnUnseenMinutes(
    const testing::WanderingPlant& plant, const NoiseRun& run, const std::string& name,
    std::vector<std::array<OmniTurnQuarter, 4>>* by_turn_rate = nullptr) {
  const std::vector<int> horizons{4, 16, 63};
  std::vector<std::vector<OmniCalibration>> minutes;
  std::vector<std::vector<PredictiveError>> pooled_rows(horizons.size());
  double period = 0;
  for (int seed : {58, 100, 101, 102, 103, 104, 105, 106}) {
    const OmniLog log = testing::RecordWanderingPlant(plant, 60, seed).log;
    const auto rows = OmniLogPredictiveErrors(run.model, log, "analytic", horizons, 2);  // CalibrateOmniLog's
    minutes.push_back(CalibrateRows(rows, horizons, log.frame_period));
    for (std::size_t q = 0; q < horizons.size(); ++q) pooled_rows[q].insert(pooled_rows[q].end(), rows[q].begin(), rows[q].end());
    period = log.frame_period;
  }
  if (by_turn_rate) *by_turn_rate = CalibrateRowsByTurnRate(pooled_rows, horizons, period);
  const std::vector<testing::PooledCalibration> pooled = testing::PoolCalibrations(minutes);
  const std::vector<double> truth{plant.noise_sd[0], plant.noise_sd[1], plant.noise_sd[2], plant.noise_correlation};
  ::testing::Test::RecordProperty(name, testing::NoiseTableRow(run.model.driving_noise, truth,
                                                               static_cast<int>(minutes.size()), pooled));
  return pooled;
}

// Measured (the noise fitted on the held-out blocks, its searches' tenth of a nat,
// 2026-12-07): forward 0.154 m/s, sideways 0.101, turn 0.846 rad/s, 0.228 s (truth 0.137,
// 0.093, 0.71, 0.23 s: within 12, 9, 19 and 1 %); a growth with speed and acceleration
// fitted but not kept (each half of the held-out blocks scored the other's worse). Over
// eight unseen minutes the 50 % ellipses hold 53 / 51 / 52 % and the 90 % ones 90 / 90 /
// 90 % at 4, 16 and 63 frames, headings 92-93 %, a single minute's shares 1-4 % apart. Fitted on the fit
// blocks as before, this minute's fit held the bands too but other minutes' did not
// (84-86 % at 16 and 63 frames); fitted on the held-out blocks, DISABLED_FittedOnOtherMinutes
// below measures them (docs/identification.md).
TEST(DrivingNoiseIdentification, AWanderingRobotsNoiseWithinThirtyPercentAndItsIntervalsCalibrated) {
  const testing::WanderingPlant plant = OffGridPlant();
  const NoiseRun run = Identify(plant);
  const OmniIdentificationReport& r = run.report;
  SCOPED_TRACE(FormatOmniIdentificationTable(r));
  ASSERT_TRUE(r.noise_identified);
  EXPECT_TRUE(r.noise.kept);
  EXPECT_LT(r.noise.held_out_after, r.noise.held_out_before);
  const char* axes[3] = {"forward", "sideways", "turn"};
  for (int a = 0; a < 3; ++a) {
    const double truth = plant.noise_sd[static_cast<std::size_t>(a)];
    EXPECT_NEAR(run.model.driving_noise.sd[static_cast<std::size_t>(a)], truth, 0.3 * truth) << axes[a];
    EXPECT_NEAR(Parameter(r, axes[a]).value, run.model.driving_noise.sd[static_cast<std::size_t>(a)], 1e-12);
  }
  EXPECT_NEAR(run.model.driving_noise.correlation_time, plant.noise_correlation, 0.3 * plant.noise_correlation);
  EXPECT_LT(run.model.driving_noise.per_speed, 0.3);  // the plant's spread is the same at every speed
  EXPECT_TRUE(run.model.driving_noise.simulated);
  ASSERT_EQ(r.calibration.size(), 3u);
  for (const OmniCalibration& c : r.calibration) EXPECT_GT(c.rows, 1000) << c.frames;
  // Calibrated already: the intervals' safeguard (issue 64), fitted at 4, 8, 16, 32 and
  // 63 frames, leaves the position's intervals within 15 % of the noise's (the unseen
  // minutes below are scored with whatever it wrote).
  EXPECT_EQ(r.safeguard.on, "held-out blocks");
  ASSERT_EQ(r.safeguard.horizons.size(), 5u);
  for (const OmniSafeguardHorizon& h : r.safeguard.horizons) EXPECT_NEAR(h.position, 1.0, 0.15) << h.frames;
  ::testing::Test::RecordProperty("same_spread_errors", StandardErrorsJson(r));
  // The bands, on eight minutes the fit never saw.
  for (const testing::PooledCalibration& p : CalibrateOnUnseenMinutes(plant, run, "same_spread")) {
    EXPECT_GT(p.pooled.rows, 8000) << p.pooled.frames;
    EXPECT_NEAR(p.pooled.position_50, 0.5, 0.05) << p.pooled.frames;
    EXPECT_NEAR(p.pooled.position_90, 0.9, 0.03) << p.pooled.frames;
  }
  // The model file carries it; the report names every parameter with an error or none.
  EXPECT_EQ(run.model.Validate(), "");
  for (const OmniNoiseParameter& p : r.noise.parameters) {
    EXPECT_TRUE(p.value > 0 || p.name.rfind("per_", 0) == 0) << p.name;
    EXPECT_EQ(p.bound, "") << p.name << " on its search's bound";
  }
}

// A robot that wanders more the faster it drives (a quarter of the spread standing,
// all of it from 1 m/s on, growing as the square): identify selects a spread growing
// with speed, which scores the held-out blocks better than none (each half's fit on the
// other half), and which at 1 m/s is the plant's within 30 % for the translation.
// Measured (2026-12-03, the spreads searched at the logs' typical motion): per_speed
// 5.7, forward 0.020 standing and 0.133 at 1 m/s (the plant's 0.034 and 0.137),
// sideways 0.014 and 0.093 (0.023 and 0.093). Over eight unseen minutes the 50 %
// ellipses hold 53 / 48 / 46 % and the 90 % ones 91 / 87 / 87 % at 4, 16 and 63 frames:
// the model's spread grows linearly with speed without end, the plant's stops growing
// at 1 m/s, and the likelihood trades the shares. (With the spreads standing still as
// coordinates, 2026-11-30: per_speed 1.38, 54 / 52 / 49 % and 90 / 87 / 87 %.)
TEST(DrivingNoiseIdentification, ASpreadGrowingWithSpeedIsSelected) {
  testing::WanderingPlant plant = OffGridPlant();
  plant.noise_still = 0.25;
  plant.noise_full_speed = 1.0;
  const NoiseRun run = Identify(plant);
  SCOPED_TRACE(FormatOmniIdentificationTable(run.report));
  EXPECT_TRUE(run.report.noise_identified);
  EXPECT_GT(run.model.driving_noise.per_speed, 0.3);
  EXPECT_TRUE(run.report.noise.growth_note.empty()) << run.report.noise.growth_note;
  for (int a = 0; a < 2; ++a) {
    const double at_speed = run.model.driving_noise.Spread(a, 1.0, 0, 0);
    const double truth = plant.noise_sd[static_cast<std::size_t>(a)];
    EXPECT_NEAR(at_speed, truth, 0.3 * truth) << a;
    EXPECT_LT(run.model.driving_noise.sd[static_cast<std::size_t>(a)], 0.6 * truth) << a;
  }
  // The bands (42-58 % and 85-95 %): the model's line cannot follow the plant's
  // saturating growth, and the shares at 16 and 63 frames sit near the tighter bands'
  // edges (87.0 % against 87).
  for (const testing::PooledCalibration& p : CalibrateOnUnseenMinutes(plant, run, "growing_spread")) {
    EXPECT_NEAR(p.pooled.position_50, 0.5, 0.08) << p.pooled.frames;
    EXPECT_NEAR(p.pooled.position_90, 0.9, 0.05) << p.pooled.frames;
  }
}

// A robot that wanders more the faster it turns (a quarter of the spread while not
// turning, all of it from 1.5 rad/s on; issue 64, where the real SSL robot's fastest
// turns were its worst covered): identify selects a spread growing with turn rate, which
// scores the held-out blocks better than none (each half's fit on the other half), and
// its fan beats a constant spread fitted on each unseen minute itself at every horizon.
// Measured (2026-12-07): 3.0 per rad/s, 0.19 per m/s, none with acceleration; over eight
// unseen minutes energy scores 2.4 / 4.8 / 5.5 % under the constant spread's at 4 / 16 /
// 63 frames, the 50 % ellipses holding 57.8 / 51 / 48 % and the 90 % ones 92 / 89 / 87 %
// (the plant's spread changes with the turn rate in steps the model's line only
// follows on average, so the 50 % band is 50 +- 8 here).
TEST(DrivingNoiseIdentification, ASpreadGrowingWithTurnRateIsSelected) {
  testing::WanderingPlant plant = OffGridPlant();
  plant.noise_not_turning = 0.25;
  plant.noise_full_turn = 1.5;
  const NoiseRun run = Identify(plant);
  SCOPED_TRACE(FormatOmniIdentificationTable(run.report));
  EXPECT_TRUE(run.report.noise.kept);
  EXPECT_GT(run.model.driving_noise.per_turn_rate, 0.3);
  EXPECT_TRUE(run.report.noise.growth_note.empty()) << run.report.noise.growth_note;
  for (const OmniSafeguardHorizon& h : run.report.safeguard.horizons) EXPECT_NEAR(h.position, 1.0, 0.15) << h.frames;
  std::vector<std::array<OmniTurnQuarter, 4>> by_turn_rate;
  for (const testing::PooledCalibration& p : CalibrateOnUnseenMinutes(plant, run, "turning_spread", &by_turn_rate)) {
    EXPECT_LT(p.pooled.energy_score, p.pooled.baseline_energy_score) << p.pooled.frames;
    EXPECT_NEAR(p.pooled.position_50, 0.5, 0.08) << p.pooled.frames;
    EXPECT_NEAR(p.pooled.position_90, 0.9, 0.04) << p.pooled.frames;
  }
  // In every quarter of the turn rate the 90 % ellipses hold at least 80 % (the issue's
  // bar for the real robot), the fastest quarter included. Measured: 91-94 % at 4
  // frames, 87-90 % at 16, 85-88 % at 63 (fastest 91, 87 and 88 %).
  SCOPED_TRACE(FormatTurnRateCalibrationTable(by_turn_rate));
  for (const std::array<OmniTurnQuarter, 4>& horizon : by_turn_rate) {
    for (const OmniTurnQuarter& q : horizon)
      EXPECT_GT(q.calibration.position_90, 0.8) << q.calibration.frames << " frames, " << q.from << "-" << q.to << " rad/s";
  }
}

// The same robot fitted on two other minutes and on three (run by
// `scripts/noise-calibration-table minutes`, some 10 minutes; not in the suites): how far
// one minute's fit strays, beside the standard errors identify reports for it. Measured
// (2026-11-29): turn 0.723 +- 0.040 and 0.707 +- 0.037 rad/s, correlation time 0.222 +-
// 0.016 and 0.201 +- 0.017 s, where seed 57's fit found 0.598 +- 0.035 and 0.271 +- 0.021
// (truth 0.71, 0.23): the minutes' fits differ by more than three of their standard
// errors. Headings then hold 89-90 % in the 90 % intervals at 4 frames (seed 57's fit
// 85 %), positions 83-84 % at 63 frames (seed 57's fit 90 %). On three minutes: turn
// 0.709, 0.223 s, translation 6 and 9 % low; headings 89-90 %, positions 89.5 / 85.6 /
// 83.9 % at 4 / 16 / 63 frames. Nothing is asserted on the numbers: it measures.
TEST(DrivingNoiseIdentification, DISABLED_FittedOnOtherMinutes) {
  const testing::WanderingPlant plant = OffGridPlant();
  const std::vector<std::vector<std::uint64_t>> fits{{61}, {65}, {61, 65, 71}};
  for (const std::vector<std::uint64_t>& seeds : fits) {
    const NoiseRun run = Identify(plant, seeds);
    const std::string name = seeds.size() == 1 ? "fit_seed_" + std::to_string(seeds[0]) : "fit_three_minutes";
    ::testing::Test::RecordProperty(name + "_errors", StandardErrorsJson(run.report));
    const std::vector<testing::PooledCalibration> pooled = CalibrateOnUnseenMinutes(plant, run, name);
    EXPECT_EQ(pooled.size(), 3u);
  }
}

// Issue 64: the validation logs' calibration split by how far the predictions' inputs lie
// from the fit's. A robot fitted while it drove gently (0.4 m/s, 1 rad/s) and scored on
// a log of the same gentle driving and on one of fast driving (1.6 m/s, 4 rad/s): the
// fast log's predictions lie mostly beyond 1 from the fit's inputs (measured 89-99 %)
// and the gentle log's none (most lie 0.25 to 1: the body's velocity, in 8 wheel speeds
// with a driving noise as large as the commands, seldom repeats the fit's closely), and
// the ranges split the whole calibration's rows, none lost or counted twice. The model is
// the plant's own with a noise; nothing is identified.
TEST(CalibrationByDistance, SplitsTheValidationRowsByHowFarTheyDriveFromTheFit) {
  testing::WanderingPlant gentle = OffGridPlant();
  gentle.max_speed = 0.4;
  gentle.max_turn = 1;
  testing::WanderingPlant fast = gentle;
  fast.max_speed = 1.6;
  fast.max_turn = 4;
  const OmniLog fit = testing::RecordWanderingPlant(gentle, 30, 61).log;
  OmniModel model = testing::ResemblingModel(testing::Omni4(), gentle);
  model.driving_noise.sd = {0.137, 0.093, 0.71};
  model.driving_noise.correlation_time = 0.23;
  const std::vector<char> fit_held(fit.rows.size(), 0);
  const std::vector<int> fit_block(fit.rows.size(), 0);
  OmniNoiseOptions options;
  auto share_far = [&](const OmniLog& scored) {
    const std::vector<char> held(scored.rows.size(), 1);
    const std::vector<int> block(scored.rows.size(), 1);
    const std::vector<OmniBlockedStretch> stretches = {{&fit, 0, &fit_held, &fit_block, false},
                                                       {&scored, 0, &held, &block, true}};
    const std::vector<OmniCalibration> whole = CalibrateOnBlocks(model, stretches, options);
    std::vector<OmniDistanceCalibration> by;
    const std::vector<OmniCalibration> split = CalibrateOnBlocks(model, stretches, options, nullptr, &by);
    for (std::size_t q = 0; q < whole.size(); ++q) EXPECT_EQ(split[q].rows, whole[q].rows);
    EXPECT_EQ(by.size(), kCalibrationDistances.size() - 1);
    int far = 0, all = 0;
    for (std::size_t q = 0; q < whole.size(); ++q) {
      int sum = 0;
      for (const OmniDistanceCalibration& d : by) sum += d.calibration[q].rows;
      EXPECT_EQ(sum, whole[q].rows) << whole[q].frames << " frames";
      far += by.back().calibration[q].rows;
      all += whole[q].rows;
    }
    EXPECT_GT(all, 500);
    return static_cast<double>(far) / all;
  };
  const double gentle_far = share_far(testing::RecordWanderingPlant(gentle, 30, 62).log);
  const double fast_far = share_far(testing::RecordWanderingPlant(fast, 30, 63).log);
  std::printf("share of rows beyond 1 from the fit's inputs: gentle %.3f, fast %.3f\n", gentle_far, fast_far);
  EXPECT_LT(gentle_far, 0.1);
  EXPECT_GT(fast_far, 0.8);
}

// Issue 64: where the held-out blocks' predicted spread comes from, beside their
// calibration and from the same rows (identify's report has it without a validation
// log). The plant is the model, wandering by 0.05, 0.05 m/s and 0.3 rad/s over 0.2 s
// (the project's own plant: this checks the bookkeeping, not a model of another robot);
// every third 3 s block held out, the first among them (whose first frames the filter's
// warm-up leaves unscored). The budget counts the calibration's rows, its parts add in
// squares to the predicted spread, and the measured error is that spread within
// the scatter of a third of a minute (measured 0.93, 0.98 and 0.92 at 4, 16 and 63
// frames; held to 0.8 to 1.2). With a validation log the calibration is there, and the
// budget left to the caller (identify's on the validation logs).
TEST(CalibrationOnBlocks, TheHeldOutBlocksSpreadBudgetCountsTheCalibrationsRows) {
  OmniModel model = testing::Omni4();
  model.driving_noise.sd = {0.05, 0.05, 0.3};
  model.driving_noise.correlation_time = 0.2;
  model.driving_noise.simulated = true;
  const OmniLog log = testing::RecordOmniPlant(model, 60, 5);
  std::vector<char> held(log.rows.size());
  std::vector<int> block(log.rows.size());
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    block[i] = static_cast<int>((log.rows[i].t - log.rows.front().t) / 3);
    held[i] = block[i] % 3 == 0;
  }
  const std::vector<OmniBlockedStretch> stretches = {{&log, 0, &held, &block, false}};
  const OmniNoiseOptions options;
  std::vector<OmniSpreadBudget> budget;
  const std::vector<OmniCalibration> calibration =
      CalibrateOnBlocks(model, stretches, options, nullptr, nullptr, nullptr, &budget);
  ASSERT_EQ(budget.size(), calibration.size());
  SCOPED_TRACE(FormatSpreadBudgets(budget));
  for (std::size_t q = 0; q < budget.size(); ++q) {
    const OmniSpreadBudget& b = budget[q];
    EXPECT_EQ(b.frames, options.horizons[q]);
    EXPECT_EQ(b.rows, calibration[q].rows) << b.frames << " frames";
    EXPECT_GT(b.rows, 50) << b.frames << " frames";
    EXPECT_GT(b.parts[kDrivingNoise], 0) << b.frames << " frames";
    double squares = b.camera * b.camera;
    for (double p : b.parts) squares += p * p;
    EXPECT_NEAR(std::sqrt(squares), b.predicted, 1e-12) << b.frames;
    EXPECT_NEAR(b.measured / b.predicted, 1.0, 0.2) << b.frames << " frames";
    std::printf("%d frames: %d rows, measured / predicted %.3f\n", b.frames, b.rows, b.measured / b.predicted);
  }
  // The same calibration with the budget asked for or not.
  const std::vector<OmniCalibration> plain = CalibrateOnBlocks(model, stretches, options);
  for (std::size_t q = 0; q < plain.size(); ++q) EXPECT_EQ(plain[q].position_50, calibration[q].position_50);

  const OmniLog other = testing::RecordOmniPlant(model, 30, 6);
  const std::vector<char> all_held(other.rows.size(), 1);
  const std::vector<int> one_block(other.rows.size(), 1 << 20);
  const std::vector<OmniBlockedStretch> validated = {{&log, 0, &held, &block, false},
                                                    {&other, 0, &all_held, &one_block, true}};
  const std::vector<OmniCalibration> on_validation =
      CalibrateOnBlocks(model, validated, options, nullptr, nullptr, nullptr, &budget);
  EXPECT_FALSE(on_validation.empty());
  EXPECT_TRUE(budget.empty());
}

}  // namespace
}  // namespace twinsim
