// The learned backend's driving noise (analysis/learned_noise.h; issue 42): the tracker's
// sampled rollouts against a closed form, the predictor file carrying the noise, the
// simulation drawing it, and a predictor's noise fitted on its held-out rows and judged
// on a log it never saw, recorded from a wandering plant (tests/estimation/
// wandering_plant.h: a first-order lag per axis, written apart from twinsim's models)
// whose driving noise the fit is never told.
#include "analysis/learned_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "analysis/omni_calibration_report.h"
#include "analysis/pooled_calibration.h"
#include "analysis/omni_replay.h"
#include "estimation/wandering_plant.h"
#include "learning/omni_predictor.h"
#include "scene/scene.h"
#include "test_util.h"

namespace twinsim {
namespace {

// A robot standing still at the origin for `seconds`, every frame measured.
OmniLog StandingLog(double seconds, double rate) {
  std::vector<OmniLogRow> rows;
  for (int k = 0; k <= static_cast<int>(std::lround(seconds * rate)); ++k) rows.push_back(OmniLogRow{k / rate, Pose2{}, Twist2{}});
  return ParseOmniLog(FormatOmniLog(rows), "standing.csv");
}

// The variance of the displacement dt sum_{k=1..K} s_k of the slip sampled exactly,
// s_k = a s_(k-1) + sqrt(1 - a^2) sd w_k from s_0 = 0: Cov(s_i, s_j) = sd^2 a^|i-j| (1 - a^(2 min(i,j))).
double SlipDisplacementVariance(double sd, double tau, double dt, int k) {
  const double a = std::exp(-dt / tau);
  double sum = 0;
  for (int i = 1; i <= k; ++i)
    for (int j = 1; j <= k; ++j) sum += sd * sd * std::pow(a, std::abs(i - j)) * (1 - std::pow(a, 2 * std::min(i, j)));
  return dt * dt * sum;
}

// The tracker's samples on a robot at rest: the wheels do not see the slip, so each
// sample's displacement is the slip's integral, whose spread is known in closed form.
TEST(TrackerSamples, ARobotAtRestSpreadsAsItsSlipIntegrates) {
  OmniModel model = testing::Omni4();
  model.driving_noise.sd = {0.12, 0.05, 0.0};
  model.driving_noise.correlation_time = 0.2;
  const OmniLog log = StandingLog(3, 60);
  OmniReplayOptions o;
  o.backend = "analytic";
  o.state = OmniReplayState::kTracker;
  o.horizon = 30;
  o.also = {6};
  o.samples = 400;
  o.stride = 40;
  const OmniReplayResult r = ReplayOmniLog(model, log, o);
  ASSERT_EQ(r.state, "tracker");
  int rows = 0;
  double vx = 0, vy = 0, vx6 = 0;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!r.predicted[i]) continue;
    ++rows;
    vx += r.covariance[i](0, 0), vy += r.covariance[i](1, 1);
    EXPECT_EQ(r.samples[i].size(), 400u);
    EXPECT_NEAR(r.pose[i].x, 0, 1e-9) << "the mean prediction is the plain one";
  }
  for (std::size_t i = 0; i < log.rows.size(); ++i)
    if (r.also[0].predicted[i]) vx6 += r.also[0].covariance[i](0, 0) / rows;
  ASSERT_GT(rows, 2);
  const double dt = 1.0 / 60;
  // 400 draws per start over `rows` starts: the variance within about 8 % (3 sigma).
  EXPECT_NEAR(vx / rows / SlipDisplacementVariance(0.12, 0.2, dt, 30), 1, 0.08);
  EXPECT_NEAR(vy / rows / SlipDisplacementVariance(0.05, 0.2, dt, 30), 1, 0.08);
  EXPECT_NEAR(vx6 / SlipDisplacementVariance(0.12, 0.2, dt, 6), 1, 0.08);
  // The same seed, the same draws; another seed, others.
  const OmniReplayResult again = ReplayOmniLog(model, log, o);
  o.seed = 2;
  const OmniReplayResult other = ReplayOmniLog(model, log, o);
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    if (!r.predicted[i]) continue;
    EXPECT_EQ(r.samples[i][7].x, again.samples[i][7].x);
    EXPECT_NE(r.samples[i][7].x, other.samples[i][7].x);
  }
}

// A wandering plant's log at 60 fps; a linear one-frame predictor trained on it.
struct Trained {
  OmniLog fit, unseen;
  OmniPredictor predictor;
};

testing::WanderingPlant LearningPlant() {
  testing::WanderingPlant plant;
  plant.noise_sd = {0.137, 0.093, 0.71};
  plant.noise_correlation = 0.23;
  return plant;
}

Trained TrainOnWanderingPlant(double seconds, const testing::WanderingPlant& plant = LearningPlant()) {
  Trained t{testing::RecordWanderingPlant(plant, seconds, 57).log, testing::RecordWanderingPlant(plant, seconds, 58).log, {}};
  OmniTrainOptions train;
  train.kind = "linear";
  train.horizon = 1;
  t.predictor = TrainOmniPredictor(testing::Omni4(), {t.fit}, train, nullptr);
  return t;
}

// The learned backend with `noisy` calibrated on `unseen` and seven more minutes of
// `plant` (seeds 100-106), pooled; recorded under `name` for
// scripts/noise-calibration-table (the table of docs/learning.md).
std::vector<testing::PooledCalibration> OnEightUnseenMinutes(const OmniPredictor& noisy, const OmniLog& unseen,
                                                             const testing::WanderingPlant& plant, const std::string& name) {
  std::vector<std::vector<OmniCalibration>> minutes{CalibrateLearnedOmniLog(testing::Omni4(), noisy, unseen)};
  for (int seed = 100; seed < 107; ++seed)
    minutes.push_back(CalibrateLearnedOmniLog(testing::Omni4(), noisy, testing::RecordWanderingPlant(plant, 60, seed).log));
  const std::vector<testing::PooledCalibration> c = testing::PoolCalibrations(minutes);
  ::testing::Test::RecordProperty(name, testing::NoiseTableRow(noisy.info().driving_noise, {}, static_cast<int>(minutes.size()), c));
  std::printf("%s", FormatCalibrationTable(minutes.front()).c_str());
  return c;
}

TEST(LearnedDrivingNoise, ThePredictorFileCarriesItAndTheSimulationDrawsIt) {
  Trained t = TrainOnWanderingPlant(20);
  EXPECT_FALSE(t.predictor.info().has_driving_noise);
  OmniDrivingNoise n;
  n.sd = {0.11, 0.07, 0.6};
  n.correlation_time = 0.3;
  n.simulated = true;
  t.predictor.SetDrivingNoise(n);
  const std::string dir = testing::TempDir("learned_noise");
  const std::string path = dir + "/noisy.pred";
  t.predictor.Save(path);
  const OmniPredictor back = OmniPredictor::Load(path);
  ASSERT_TRUE(back.info().has_driving_noise);
  EXPECT_EQ(back.info().driving_noise.sd, n.sd);
  EXPECT_EQ(back.info().driving_noise.correlation_time, n.correlation_time);
  EXPECT_TRUE(back.info().driving_noise.simulated);

  // A learned robot takes the predictor's noise; --driving-noise off turns it off; a
  // robot on a physics backend keeps its model's.
  Scene scene = LoadSceneFromString(
      "name: s\nbackend: learned\nframe_rate: 60\nduration: 1\nrobots:\n  - name: a\n    model: " +
          testing::SourcePath("models/omni4.yaml") + "\n    start: {x: 0, y: 0, theta_deg: 0}\n    commands: {type: random}\n",
      "s.yaml", ".");
  const auto shared = std::make_shared<const OmniPredictor>(back);
  const SceneRobot& robot = scene.robots[0];
  EXPECT_EQ(SimulatedRobotModel(scene, robot, {"learned", shared}).driving_noise.sd, n.sd);
  EXPECT_TRUE(SimulatedRobotModel(scene, robot, {"learned", shared}).driving_noise.simulated);
  EXPECT_NE(SimulatedRobotModel(scene, robot, {"analytic", shared}).driving_noise.sd, n.sd);
  scene.driving_noise = "off";
  EXPECT_FALSE(SimulatedRobotModel(scene, robot, {"learned", shared}).driving_noise.simulated);

  // Two runs of the learned backend, the noise on: the same seed the same path, and not
  // the path without the noise.
  scene.driving_noise = "model";
  OmniBackendOptions options;
  options.predictor = shared;
  const SimulationResult a = MakeSimulation(scene, "learned", options).Run(scene.num_frames());
  const SimulationResult b = MakeSimulation(scene, "learned", options).Run(scene.num_frames());
  scene.driving_noise = "off";
  const SimulationResult c = MakeSimulation(scene, "learned", options).Run(scene.num_frames());
  EXPECT_EQ(a.frames[0].back().truth.x, b.frames[0].back().truth.x);
  EXPECT_NE(a.frames[0].back().truth.x, c.frames[0].back().truth.x);

  // A file whose predictor looks further ahead than a frame cannot carry one.
  std::string text = testing::ReadText(path);
  text.replace(text.find("horizon: 1"), 10, "horizon: 4");
  EXPECT_THROW(OmniPredictor::Load(testing::WriteText(dir + "/far.pred", text)), InputError);
}

// What loading the predictor file at `path` throws ("" when it loads).
std::string LoadError(const std::string& path) {
  try {
    OmniPredictor::Load(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A learned prediction's distance from the predictor's training (OmniBackend::
// TakeInputExcess, the largest InputExcess of its rollout's steps): a linear predictor
// trained on a robot driven slowly, its log replayed, goes nowhere beyond its range
// (every row below 0.25, where the backend counts nothing unseen); a robot driven four
// times as fast takes most 1 s predictions beyond a whole span. A longer prediction from
// the same start went at least as far as a shorter one, and the calibration by distance
// splits the same rows the whole calibration scores.
TEST(LearnedInputDistance, PredictionsAreScoredByHowFarTheirInputsWentBeyondTraining) {
  const OmniModel m = testing::Omni4();
  const OmniLog slow = testing::RecordLog(m, testing::RandomDrive(0.5, 0.5, 2.0), 40, 21, "analytic", "slow.csv");
  const OmniLog fast = testing::RecordLog(m, testing::RandomDrive(2.0, 2.0, 2.0), 20, 22, "analytic", "fast.csv");
  OmniPredictor p = TrainOmniPredictor(m, {slow}, OmniTrainOptions{});
  OmniDrivingNoise n;
  n.sd = {0.02, 0.02, 0.1};
  n.correlation_time = 0.05;
  n.simulated = true;
  p.SetDrivingNoise(n);
  ASSERT_FALSE(p.info().input_low.empty());

  OmniReplayOptions o;
  o.backend = "learned";
  o.backend_options.predictor = std::make_shared<const OmniPredictor>(p);
  o.horizon = 30;
  o.also = {3};
  const OmniReplayResult own = ReplayOmniLog(m, slow, o);
  const OmniReplayResult far = ReplayOmniLog(m, fast, o);
  ASSERT_EQ(far.input_distance.size(), fast.rows.size());
  ASSERT_EQ(far.also[0].input_distance.size(), fast.rows.size());
  int own_rows = 0, beyond = 0, far_rows = 0;
  double own_largest = 0;
  for (std::size_t i = 0; i < slow.rows.size(); ++i) {
    if (!own.predicted[i]) continue;
    ++own_rows;
    own_largest = std::max(own_largest, own.input_distance[i]);
  }
  std::map<int, std::size_t> row_of_frame;
  for (std::size_t i = 0; i < fast.rows.size(); ++i) row_of_frame[fast.FrameIndex(i)] = i;
  int pairs = 0;
  for (std::size_t i = 0; i < fast.rows.size(); ++i) {
    if (!far.predicted[i]) continue;
    ++far_rows;
    beyond += far.input_distance[i] > 1;
    // The row 27 frames earlier, predicted 3 frames from the same start: no farther.
    const auto shorter = row_of_frame.find(fast.FrameIndex(i) - 27);
    if (shorter != row_of_frame.end() && far.also[0].predicted[shorter->second]) {
      EXPECT_LE(far.also[0].input_distance[shorter->second], far.input_distance[i]) << i;
      ++pairs;
    }
  }
  EXPECT_GT(pairs, far_rows / 2);
  ASSERT_GT(own_rows, 500);
  EXPECT_LT(own_largest, 0.25);  // its own log holds nothing unseen (the backend's own rule)
  EXPECT_GT(beyond, far_rows / 2);

  std::vector<OmniDistanceCalibration> by_distance;
  LearnedNoiseOptions every;
  every.stride = 8;
  const std::vector<OmniCalibration> whole = CalibrateLearnedOmniLog(m, p, fast, every, nullptr, &by_distance);
  ASSERT_EQ(by_distance.size(), 3u);
  for (std::size_t h = 0; h < whole.size(); ++h) {
    int split = 0;
    for (const OmniDistanceCalibration& d : by_distance) split += d.calibration[h].rows;
    EXPECT_EQ(split, whole[h].rows) << whole[h].frames;
  }
  EXPECT_GT(by_distance.back().calibration.back().rows, whole.back().rows / 2);  // 63 frames: mostly beyond 1
}

// The intervals' safeguard in the predictor file (issue 64): the file carries the scales
// per horizon, refuses them without a driving noise to scale or with a growth, and the
// learned backend's sampled rollouts spread about the prediction by exactly them, the
// same draws otherwise.
TEST(LearnedIntervalSafeguard, TheFileCarriesItAndTheRolloutsSpreadByIt) {
  Trained t = TrainOnWanderingPlant(20);
  OmniDrivingNoise n;
  n.sd = {0.11, 0.07, 0.6};
  n.correlation_time = 0.3;
  n.simulated = true;
  t.predictor.SetDrivingNoise(n);
  OmniPredictor scaled = t.predictor;
  scaled.SetIntervalScale({{4, 1.5, 0.5}, {16, 2.0, 3.0}});
  const std::string dir = testing::TempDir("learned_safeguard");
  scaled.Save(dir + "/scaled.pred");
  const OmniPredictor back = OmniPredictor::Load(dir + "/scaled.pred");
  ASSERT_EQ(back.info().interval_scale.size(), 2u);
  EXPECT_EQ(back.info().interval_scale[1].frames, 16);
  EXPECT_EQ(back.info().interval_scale[1].position, 2.0);
  EXPECT_EQ(back.info().interval_scale[1].heading, 3.0);

  OmniReplayOptions o;
  o.backend = "learned";
  o.horizon = 16;
  o.also = {4};
  o.samples = 8;
  o.stride = 25;
  o.backend_options.predictor = std::make_shared<OmniPredictor>(t.predictor);
  const OmniReplayResult plain = ReplayOmniLog(testing::Omni4(), t.unseen, o);
  o.backend_options.predictor = std::make_shared<OmniPredictor>(back);
  const OmniReplayResult wide = ReplayOmniLog(testing::Omni4(), t.unseen, o);
  int rows = 0;
  for (std::size_t i = 0; i < t.unseen.rows.size(); ++i) {
    if (!plain.predicted[i]) continue;
    ++rows;
    ASSERT_EQ(wide.pose[i].x, plain.pose[i].x) << "the mean prediction is the plain one";
    const Pose2& p = plain.samples[i][3];
    const Pose2& w = wide.samples[i][3];
    EXPECT_NEAR(w.x - wide.pose[i].x, 2 * (p.x - plain.pose[i].x), 1e-12);
    EXPECT_NEAR(w.theta - wide.pose[i].theta, 3 * (p.theta - plain.pose[i].theta), 1e-12);
    const Eigen::Vector3d d(2, 2, 3);
    EXPECT_TRUE(wide.covariance[i].isApprox(d.asDiagonal() * plain.covariance[i] * d.asDiagonal(), 1e-12)) << i;
    if (!plain.also[0].predicted[i]) continue;
    const Eigen::Vector3d d4(1.5, 1.5, 0.5);
    EXPECT_TRUE(wide.also[0].covariance[i].isApprox(d4.asDiagonal() * plain.also[0].covariance[i] * d4.asDiagonal(), 1e-12));
  }
  EXPECT_GT(rows, 20);

  // Bad files: a scale without a noise to scale, a growth (a physics model's only).
  std::string text = testing::ReadText(dir + "/scaled.pred");
  std::string no_noise = text;
  no_noise.erase(no_noise.find("driving_noise:"), no_noise.find('\n', no_noise.find("driving_noise:")) + 1 -
                                                      no_noise.find("driving_noise:"));
  EXPECT_NE(LoadError(testing::WriteText(dir + "/no_noise.pred", no_noise)).find("scales the driving noise's intervals"),
            std::string::npos);
  std::string growth = text;
  growth.replace(growth.find("heading: 3}"), 11, "heading: 3, position_growth: 1}");
  EXPECT_NE(LoadError(testing::WriteText(dir + "/growth.pred", growth)).find("position_growth"), std::string::npos);
}

// A learned backend whose driving noise is a third of what the robot wanders (the
// wandering plant's spreads over 3): its 90 % ellipses hold far too little. The
// safeguard `train` fits on the same held-out rows (the last 12 s of the minute, its two
// halves as folds) widens the rollouts, and on a minute the predictor never saw the 90 %
// ellipses then hold about their share. The fit is never told the plant's spreads or
// the factor. Measured (2026-12-04): position scales 4.2, 2.7, 1.7 and 1.5 at 4, 8, 16
// and 32 frames; the unseen minute's 90 % ellipses 25.6 -> 94.5 % at 4 frames and
// 57.6 -> 86.1 % at 16. At 63 frames the held-out rows held 80 % (the narrow slip
// integrates to a nearer spread there), and 113 predictions over 63 frames are some 7
// independent stretches, whose share is uncertain by 11 %: the safeguard leaves that
// horizon as it is (the unseen minute holds 83.5 % there), as its rule says.
TEST(LearnedIntervalSafeguard, WidensANoiseTooNarrowToHoldItsShareOnAnUnseenMinute) {
  Trained t = TrainOnWanderingPlant(60);
  const testing::WanderingPlant plant = LearningPlant();
  OmniDrivingNoise narrow;
  for (std::size_t a = 0; a < 3; ++a) narrow.sd[a] = plant.noise_sd[a] / 3;
  narrow.correlation_time = plant.noise_correlation;
  narrow.simulated = true;
  t.predictor.SetDrivingNoise(narrow);
  const OmniIntervalSafeguard g = FitLearnedIntervalSafeguard(testing::Omni4(), t.predictor, OmniValidationParts({t.fit}, 0.2));
  SCOPED_TRACE(FormatSafeguard(g, 1.0 / 60));
  EXPECT_EQ(g.on, "held-out rows, each log's halves as folds");
  ASSERT_EQ(g.horizons.size(), 5u);  // 4, 8, 16, 32, 63 frames
  for (const OmniSafeguardHorizon& h : g.horizons) {
    if (h.frames > 16) continue;
    EXPECT_TRUE(h.position_kept) << h.frames;
    EXPECT_GT(h.position, 1.5) << h.frames;
  }
  EXPECT_FALSE(g.horizons.back().position_kept);
  OmniPredictor safeguarded = t.predictor;
  safeguarded.SetIntervalScale(g.Scales());
  const std::vector<OmniCalibration> before = CalibrateLearnedOmniLog(testing::Omni4(), t.predictor, t.unseen);
  const std::vector<OmniCalibration> after = CalibrateLearnedOmniLog(testing::Omni4(), safeguarded, t.unseen);
  std::printf("%swithout the safeguard:\n%swith it:\n%s", FormatSafeguard(g, 1.0 / 60).c_str(),
              FormatCalibrationTable(before).c_str(), FormatCalibrationTable(after).c_str());
  ASSERT_EQ(after.size(), 3u);
  for (std::size_t q = 0; q < 2; ++q) {  // 4 and 16 frames
    EXPECT_LT(before[q].position_90, 0.75) << after[q].frames;
    EXPECT_GT(after[q].position_90, 0.84) << after[q].frames;
    EXPECT_LT(after[q].position_90, 0.96) << after[q].frames;
    EXPECT_LT(after[q].log_score, before[q].log_score) << after[q].frames;
  }
}

// Fitted on the held-out 20 % of one minute, judged on eight minutes it never saw: the
// 50 % and 90 % ellipses of the learned backend's sampled rollouts hold about their
// share at 4, 16 and 63 frames. Measured: the 50 % ellipses hold 52/56/51 %, the 90 %
// ones 91/92/90 % (docs/learning.md, "The learned backend's driving noise"). The fit's
// 12 s hold some 50 independent stretches of the wander, so the fitted spread is
// uncertain by about 10 %: fitted on this minute and three others, the 16-frame 50 %
// ellipse held 42 to 57 % (docs/learning.md), so the test accepts 44-60 % and 86-95 %. The correlation
// time comes out an eighth of the plant's 0.23 s: the predictor carries a slip on from
// the frames it sees.
TEST(LearnedDrivingNoise, FittedOnHeldOutRowsCalibratedOnUnseenMinutes) {
  const Trained t = TrainOnWanderingPlant(60);
  const LearnedNoiseFit fit = FitLearnedDrivingNoise(testing::Omni4(), t.predictor, OmniValidationParts({t.fit}, 0.2));
  SCOPED_TRACE(FormatLearnedNoiseFit(fit));
  EXPECT_LT(fit.cost_after, fit.cost_before);
  EXPECT_TRUE(fit.noise.simulated);
  OmniPredictor noisy = t.predictor;
  noisy.SetDrivingNoise(fit.noise);
  const std::vector<testing::PooledCalibration> c = OnEightUnseenMinutes(noisy, t.unseen, LearningPlant(), "table_row");
  ASSERT_EQ(c.size(), 3u);
  for (const testing::PooledCalibration& p : c) {
    const OmniCalibration& h = p.pooled;
    EXPECT_GT(h.rows, 4000) << h.frames;
    EXPECT_GT(h.position_50, 0.44) << h.frames;
    EXPECT_LT(h.position_50, 0.60) << h.frames;
    EXPECT_GT(h.position_90, 0.86) << h.frames;
    EXPECT_LT(h.position_90, 0.95) << h.frames;
  }
  // Without it (a hundredth of the spread) the intervals are far too narrow.
  OmniDrivingNoise tiny = fit.noise;
  for (double& s : tiny.sd) s /= 100;
  noisy.SetDrivingNoise(tiny);
  EXPECT_LT(CalibrateLearnedOmniLog(testing::Omni4(), noisy, t.unseen).back().position_90, 0.5);
}

// A robot that wanders more the faster it turns (a quarter of the spread while not
// turning, all of it from 1.5 rad/s on; issue 64): the fit's growth with turn rate,
// searched about the logs' typical motion as the growth with speed is, takes it up, and
// the fan's shape then beats a constant spread at every horizon over eight unseen
// minutes (its energy score lower). Measured (2026-12-03): 1.3 per rad/s (and 0.9 per
// m/s); energy scores 0.9, 3.8 and 5.1 % under the constant spread's at 4, 16 and 63
// frames on the first unseen minute, where the fit without the turn rate's growth (1.55
// per m/s) scored -1.3, 0.0 and 2.4 % and held 62 and 67 % in its pooled 50 % ellipses
// at 4 and 16 frames. With it the 90 % ellipses hold the test above's band, the 50 %
// ones 61, 63 and 50 %: errors that mix turning and standing are heavier-tailed than
// the rollouts' Student t at one spread, so the 50 % band is 44-65 % here.
TEST(LearnedDrivingNoise, ASpreadGrowingWithTurnRateIsFitted) {
  testing::WanderingPlant plant = LearningPlant();
  plant.noise_not_turning = 0.25;
  plant.noise_full_turn = 1.5;
  const Trained t = TrainOnWanderingPlant(60, plant);
  const LearnedNoiseFit fit = FitLearnedDrivingNoise(testing::Omni4(), t.predictor, OmniValidationParts({t.fit}, 0.2));
  SCOPED_TRACE(FormatLearnedNoiseFit(fit));
  EXPECT_GT(fit.noise.per_turn_rate, 0.3);
  OmniPredictor noisy = t.predictor;
  noisy.SetDrivingNoise(fit.noise);
  const std::vector<testing::PooledCalibration> c = OnEightUnseenMinutes(noisy, t.unseen, plant, "turning_table_row");
  ASSERT_EQ(c.size(), 3u);
  for (const testing::PooledCalibration& p : c) {
    const OmniCalibration& h = p.pooled;
    EXPECT_LT(h.energy_score, h.baseline_energy_score) << h.frames;
    EXPECT_GT(h.position_50, 0.44) << h.frames;
    EXPECT_LT(h.position_50, 0.65) << h.frames;
    EXPECT_GT(h.position_90, 0.86) << h.frames;
    EXPECT_LT(h.position_90, 0.95) << h.frames;
  }
}

}  // namespace
}  // namespace twinsim
