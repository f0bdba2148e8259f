// The real Festo Robotino of ../shared/realdata/robotino (168 runs on four floors and
// across two; skipped when ../shared is absent): every run reads, clock holes included,
// and the diagnosis's change finder lists the floor changes and not the single floors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/omni_calibration.h"
#include "analysis/omni_replay.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "diagnosis/response_changes.h"
#include "engines/omni_engine.h"
#include "identification_omni/omni_identification.h"
#include "learning/omni_predictor.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::string RobotinoDir() { return testing::SourcePath("../shared/realdata/robotino"); }

// The runs of one folder ("gray_surface"), sorted, whose file name starts with `prefix`.
std::vector<std::string> Runs(const std::string& folder, const std::string& prefix = "v") {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(RobotinoDir() + "/" + folder)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().extension() == ".csv") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Gray floor at 0.2 m/s: the four runs along the robot's axes (fit) and the four 30
// degrees from them (held).
void GrayRuns(std::vector<OmniLog>* fit, std::vector<OmniLog>* held) {
  const std::string gray = RobotinoDir() + "/gray_surface/";
  for (const char* d : {"d000", "d090", "d180", "d270"}) fit->push_back(ReadOmniLog(gray + "v0.2_" + d + ".csv"));
  for (const char* d : {"d030", "d120", "d210", "d300"}) held->push_back(ReadOmniLog(gray + "v0.2_" + d + ".csv"));
}

#define SKIP_WITHOUT_ROBOTINO()                                             \
  if (!std::filesystem::exists(RobotinoDir() + "/README.md")) GTEST_SKIP() \
      << "no real data at " << RobotinoDir()

TEST(Robotino, EveryRunReadsAndTheLoggersStallsAreHoles) {
  SKIP_WITHOUT_ROBOTINO();
  int runs = 0, stalled = 0;
  for (const char* folder : {"gray_surface", "green_surface", "table_surface", "brown_surface", "across_green_table",
                             "across_table_gray"}) {
    for (const std::string& path : Runs(folder)) {
      const OmniLog log = ReadOmniLog(path);  // before issue 63, 7 runs were refused: "irregular frame time"
      ++runs;
      // The README: stalls of 6-8 frame periods (5 to 7 frames without a row); besides,
      // the clock jitters to 1.66 periods, a missed frame.
      bool stall = false;
      for (const ClockHole& h : log.holes) {
        EXPECT_LE(h.frames, 7) << path;
        stall = stall || h.frames >= 4;
      }
      stalled += stall;
    }
  }
  EXPECT_EQ(runs, 168);
  EXPECT_EQ(stalled, 7);
}

// Issue 63's numbers: a change listed on at least 80 % of the runs across green and
// table at 0.2 and 0.3 m/s (measured: 22 of 24; both misses drive at 30 degrees, where
// the two floors differ least), on at most 3 of the 60 single-floor runs of gray, table
// and brown (measured: none).
TEST(Robotino, TheChangeFinderListsFloorChangesAndNotSingleFloors) {
  SKIP_WITHOUT_ROBOTINO();
  const OmniModel model = LoadOmniModel(testing::SourcePath("models/robotino.yaml"));
  int across = 0, found = 0;
  for (const char* speed : {"v0.2", "v0.3"}) {
    for (const std::string& path : Runs("across_green_table", speed)) {
      ++across;
      const std::vector<ResponseChange> c = FindOmniResponseChanges(model, {ReadOmniLog(path)}, "analytic");
      found += !c.empty();
      for (const ResponseChange& x : c) {
        EXPECT_EQ(x.quantity, "velocity scale") << path;  // omega is never commanded
        EXPECT_GT(x.t, 0.5) << path;
      }
    }
  }
  EXPECT_EQ(across, 24);
  EXPECT_GE(found, 20) << "of " << across << " runs across green and table at 0.2 and 0.3 m/s";
  int single = 0, flagged = 0;
  for (const char* folder : {"gray_surface", "table_surface", "brown_surface"}) {
    for (const std::string& path : Runs(folder)) {
      ++single;
      const std::vector<ResponseChange> c = FindOmniResponseChanges(model, {ReadOmniLog(path)}, "analytic");
      flagged += !c.empty();
      for (const ResponseChange& x : c) std::printf("on one floor: %s: %s\n", x.log.c_str(), x.what.c_str());
    }
  }
  std::printf("changes listed on %d of %d runs across green and table, on %d of %d single-floor runs\n", found, across,
              flagged, single);
  EXPECT_EQ(single, 60);
  EXPECT_LE(flagged, 3) << "of " << single << " single-floor runs";
}

// identify on some runs of a floor predicts the others (issue 63): four runs of gray at
// 0.2 m/s fitted, four other directions held out wholly. Measured: position error 2.8 mm
// at 4 frames against 5.5 for constant velocity and 6.2 for the published geometry, 12.2
// against 34.4 and 72.3 mm at 1 s; 20 s on two cores.
TEST(Robotino, IdentifiedOnFourRunsOfAFloorPredictsFourOthers) {
  SKIP_WITHOUT_ROBOTINO();
  std::vector<OmniLog> fit, held;
  GrayRuns(&fit, &held);
  OmniModel identified;
  const OmniIdentificationReport report =
      IdentifyOmni(LoadOmniModel(testing::SourcePath("models/robotino.yaml")), fit, held, {}, &identified);
  SCOPED_TRACE(FormatOmniIdentificationTable(report));
  EXPECT_EQ(identified.fitted_on, "analytic");
  // The camera (a motion-capture system's poses) is better than the observer's floor of
  // 0.5 mm: the report says the noise's camera_xy sits on its bound (issue 64). With the
  // floors at 0.1 mm and 1 mrad it went to 0.46 mm and 4.2 mrad and the validation runs'
  // calibration moved by a few points only (docs/identification.md).
  ASSERT_TRUE(report.noise_identified);
  for (const OmniNoiseParameter& p : report.noise.parameters) {
    if (p.name == "camera_xy") {
      EXPECT_EQ(p.bound, "lower");
    }
  }
  // The four axis runs alias a three-wheel robot's turn by direction onto its couplings:
  // the report says its turn between them is not checked (issue 64: on the runs 30
  // degrees from them the heading's 90 % intervals held 37 % at 63 frames).
  EXPECT_TRUE(std::any_of(report.notes.begin(), report.notes.end(), [](const std::string& n) {
    return n.find("too few directions to tell its turn by direction") != std::string::npos;
  }));
  // The validation runs' calibration split by distance from the fit's inputs (issue 64):
  // every row in one range (measured: all 0.25 to 1, the runs 30 degrees from the fit's).
  ASSERT_EQ(report.calibration_by_distance.size(), kCalibrationDistances.size() - 1);
  for (std::size_t q = 0; q < report.calibration.size(); ++q) {
    int rows = 0;
    for (const OmniDistanceCalibration& d : report.calibration_by_distance) rows += d.calibration[q].rows;
    EXPECT_EQ(rows, report.calibration[q].rows) << report.calibration[q].frames << " frames";
  }
  // Where the spread comes from on the validation runs (issue 64): at 16 frames the
  // driving noise, fitted on the 4- and 8-frame predictions the 0.5 s blocks hold, is
  // most of it and the intervals are too wide (measured 3.8 against 6.5 mm; the slip
  // 5.8; docs/identification.md, "Where the spread comes from").
  ASSERT_EQ(report.spread_budget.size(), report.calibration.size());
  EXPECT_EQ(report.spread_budget_on, "validation logs");
  for (const OmniSpreadBudget& b : report.spread_budget) {
    EXPECT_GT(b.rows, 200) << b.frames;
    if (b.frames != 16) continue;
    EXPECT_LT(b.measured, 0.7 * b.predicted);
    for (int p = 0; p < kCovarianceParts; ++p) EXPECT_LE(b.parts[static_cast<std::size_t>(p)], b.parts[kDrivingNoise]);
  }
  ASSERT_GE(report.horizons.size(), 3u);
  for (const OmniHorizonGaps& h : report.horizons) {
    const OmniGap* ident = report.Gap(h.gaps, "identified model");
    const OmniGap* cv = report.Gap(h.gaps, "constant velocity");
    const OmniGap* nominal = report.Gap(h.gaps, "nominal model");
    ASSERT_TRUE(ident && cv && nominal);
    EXPECT_LT(ident->rmse, nominal->rmse) << h.label;
    EXPECT_LT(ident->rmse, (h.frames <= 4 ? 0.65 : 0.5) * cv->rmse) << h.label;
  }
  // One model, every engine: the held-out runs replayed as `replay` does on each engine
  // agree within 5 % (issue 63). Before ODE placed its robot at its static sink, ODE
  // predicted them at 6.0 mm against 2.9.
  for (const OmniLog& log : held) {
    std::vector<double> rmse;
    for (const std::string& engine : AvailableOmniEngines()) {
      OmniReplayOptions o;
      o.backend = engine;
      rmse.push_back(PositionRmse(log, ReplayOmniLog(identified, log, o)));
    }
    for (std::size_t e = 1; e < rmse.size(); ++e)
      EXPECT_NEAR(rmse[e], rmse[0], 0.05 * rmse[0]) << log.path << ": " << AvailableOmniEngines()[e];
  }
  // The diagnosis of two held-out runs against the identified model (issue 63): the noise
  // floor is never above the model's own error on the runs' fit rows. Where the model's
  // driving noise says the robot wanders more than it does, the floor drawn with it is
  // held at that error and the report says so. Identify's noise sits on that edge here:
  // whether its growth with acceleration is kept turns on the last digits of its
  // arithmetic (kept, the wander drawn half a second ahead is 7.3 mm against the model's
  // own 3.7 mm; not kept, measured with the engine's stages turned rather than their
  // sines taken, 3.9 against 3.8: docs/benchmarks.md), so the note is checked on the
  // same model with its driving noise doubled.
  for (const double noise_factor : {1.0, 2.0}) {
    OmniModel model = identified;
    for (double& sd : model.driving_noise.sd) sd *= noise_factor;
    const DiagnosisReport diagnosis = DiagnoseOmni(model, {held[1], held[3]}, DiagnosisOptions{});
    SCOPED_TRACE(FormatDiagnosisTable(diagnosis));
    EXPECT_LE(diagnosis.noise_floor, diagnosis.fit_gap_before * (1 + 1e-12)) << noise_factor;
    if (noise_factor == 1.0) continue;
    EXPECT_TRUE(std::any_of(diagnosis.notes.begin(), diagnosis.notes.end(), [](const std::string& n) {
      return n.find("this robot wanders less than the noise says") != std::string::npos;
    }));
  }
  // The hybrid over the identified model (`train --residual`, then the learned backend),
  // here beside the identification it needs: the physics already predicts these runs
  // within a few mm, and four straight runs teach a 48-input correction little that holds
  // in another direction. Once the physics learned each run's drift (driving_noise.drift),
  // the sideways correction the one-frame cross-validation kept (ridge 10) lost up to
  // 1.76x to it a second ahead (10.8 against 6.1 mm on the 120-degree run). The rollout
  // check (1 s rollouts cross-validated over the fit runs, docs/learning.md) drops it:
  // the hybrid is its physics rolled out by the learned backend, measured within 1.09x
  // at 1 s and equal at 4 frames; held to 1.2x.
  OmniTrainOptions train;
  train.residual = true;
  train.choose_nominal_state = true;  // as `train --residual` does
  OmniTrainSummary summary;
  auto hybrid = std::make_shared<OmniPredictor>(TrainOmniPredictor(identified, fit, train, &summary));
  SCOPED_TRACE(summary.BriefReport());
  EXPECT_EQ(summary.ridge_folds, "4 logs");
  EXPECT_EQ(summary.rollout_check.folds, 4);
  EXPECT_LE(summary.rollout_check.rmse_kept, summary.rollout_check.rmse_chosen);
  for (const OmniLog& log : held) {
    for (int horizon : {4, 32}) {
      OmniReplayOptions physics;
      physics.backend = "analytic";
      physics.horizon = horizon;
      OmniReplayOptions learned = physics;
      learned.backend = "learned";
      learned.backend_options.predictor = hybrid;
      const double p = PositionRmse(log, ReplayOmniLog(identified, log, physics));
      const double h = PositionRmse(log, ReplayOmniLog(identified, log, learned));
      EXPECT_LT(h, 1.2 * p)
          << log.path << " at " << horizon << " frames: hybrid " << h * 1000 << " mm, physics " << p * 1000 << " mm";
    }
  }
}

// Issue 64: identified with the left-out logs (--safeguard logs), each predicted by the
// model of the other three (90 degrees from the nearest fit direction). Before the noise
// had a drift they asked for a scale growing with the distance from the fit's inputs at
// 16 and 63 frames, and with it the validation runs (30 degrees from the fit directions)
// had a 63-frame log density of -5.3 nats per row, pooled (-0.3 with the filter's own
// covariance). Now the drift fitted on the left-out logs carries each run's own
// deviation: it is kept, no position scale is needed from 16 frames on, and the
// validation runs' 63-frame log density is -8.1 nats per row as identify writes the model
// (lower is better; -10.1 with the filter's covariance alone: the heading scale kept at 4
// and 8 frames, held beyond them, widens the long horizons' headings too, which costs
// more there than it buys; docs/identification.md, "A run's own drift").
TEST(Robotino, TheLeftOutLogsDriftCarriesTheRunsBetweenThem) {
  SKIP_WITHOUT_ROBOTINO();
  std::vector<OmniLog> fit, held;
  GrayRuns(&fit, &held);
  OmniIdentificationOptions options;
  options.safeguard = OmniSafeguard::kLogs;
  OmniModel grown;
  const OmniIdentificationReport report =
      IdentifyOmni(LoadOmniModel(testing::SourcePath("models/robotino.yaml")), fit, {}, options, &grown);
  EXPECT_NE(report.safeguard.on.find("left-out logs"), std::string::npos);
  ASSERT_TRUE(report.drift_identified);
  EXPECT_TRUE(report.drift.kept) << report.drift.note;
  EXPECT_NE(report.drift.on.find("left-out logs"), std::string::npos) << report.drift.on;
  EXPECT_EQ(grown.driving_noise.drift.sd, report.drift.drift.sd);
  EXPECT_LT(report.drift.rmse_after[1], 0.6 * report.drift.rmse_before[1]) << "the left-out logs a second ahead";
  EXPECT_EQ(grown.Validate(), "");
  double score = 0, distance = 0;
  int rows = 0;
  for (const OmniLog& log : held) {
    const auto g = OmniLogPredictiveErrors(grown, log, "analytic", {16, 63}, 2)[1];
    score += MeanLogScore(g) * static_cast<double>(g.size());
    for (const PredictiveError& r : g) distance += r.input_distance;
    rows += static_cast<int>(g.size());
  }
  ASSERT_GT(rows, 100);
  if (!grown.observer.seen_inputs.empty()) {
    EXPECT_LT(distance / rows, 1.0);
  }
  EXPECT_LT(score / rows, -6.5) << "the validation runs 63 frames ahead (before the drift: -5.3 with the growth)";
}

// Issue 64: six runs of gray at 0.2 m/s every 60 degrees identified with the left-out
// logs (--safeguard logs); the six between them, 30 degrees from every fit direction,
// scored. Ten-second runs leave no held-out block long enough for a prediction 0.5 s
// ahead, so nothing within the fit's reach checks the intervals there, and until the
// left-out logs could fit a scale of their own where the blocks have none (a growth over
// 1 only widens), the headings' 90 % regions held 99.7 % of the scored runs at 16 frames.
// Measured now: the left-out logs narrow position and heading at 16 and 32 frames (x0.56
// and x0.44 at 16); on the scored runs the heading's 90 % regions hold 96.5 % at 16
// frames and the log score is -11.66 nats per row (before -11.44; lower is better), the
// position's 75.3 % (87.9 before): the runs between the fit directions turn off the
// model by up to 18 mrad/s, more than any left-out fit direction does.
TEST(Robotino, WhereNoHeldOutBlockReachesTheLeftOutLogsScaleTheIntervalsThemselves) {
  SKIP_WITHOUT_ROBOTINO();
  const std::string gray = RobotinoDir() + "/gray_surface/v0.2_";
  std::vector<OmniLog> fit, scored;
  for (const char* d : {"d000", "d060", "d120", "d180", "d240", "d300"}) fit.push_back(ReadOmniLog(gray + d + ".csv"));
  for (const char* d : {"d030", "d090", "d150", "d210", "d270", "d330"}) scored.push_back(ReadOmniLog(gray + d + ".csv"));
  OmniIdentificationOptions options;
  options.safeguard = OmniSafeguard::kLogs;
  OmniModel model;
  const OmniIdentificationReport report =
      IdentifyOmni(LoadOmniModel(testing::SourcePath("models/robotino.yaml")), fit, {}, options, &model);
  SCOPED_TRACE(FormatOmniIdentificationTable(report));
  EXPECT_NE(report.safeguard.on.find("a scale of their own"), std::string::npos) << report.safeguard.on;
  const OmniSafeguardHorizon* at16 = nullptr;
  for (const OmniSafeguardHorizon& h : report.safeguard.horizons)
    if (h.frames == 16) at16 = &h;
  ASSERT_NE(at16, nullptr);
  EXPECT_TRUE(at16->heading_kept);
  EXPECT_LT(at16->heading, 0.7) << "the left-out logs narrow the headings";
  std::vector<std::vector<PredictiveError>> rows(1);
  for (const OmniLog& log : scored) {
    const auto r = OmniLogPredictiveErrors(model, log, "analytic", {16}, 2)[0];
    rows[0].insert(rows[0].end(), r.begin(), r.end());
  }
  const OmniCalibration c = CalibrateRows(rows, {16}, fit[0].frame_period)[0];
  ASSERT_GT(c.rows, 300);
  EXPECT_LT(c.heading_90, 0.98);
  EXPECT_LT(c.log_score, -11.5);
}

}  // namespace
}  // namespace twinsim
