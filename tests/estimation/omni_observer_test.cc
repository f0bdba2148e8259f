#include "estimation/omni_observer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "analysis/omni_replay.h"
#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "estimation/wandering_plant.h"
#include "test_util.h"

namespace twinsim {
namespace {

OmniModel ResemblingModel(const testing::WanderingPlant& plant) {
  return testing::ResemblingModel(testing::Omni4(), plant);
}

OmniReplayOptions Options(OmniReplayState state, int horizon = 4) {
  OmniReplayOptions o;
  o.backend = "analytic";
  o.horizon = horizon;
  o.state = state;
  return o;
}

// The seed's use: the pose four frames ahead of the camera (the delay predicted away).
// On a robot whose velocity is largely driving noise, the open-loop tracker loses even
// to no model; the observer, which estimates the velocity from the camera, beats both.
TEST(OmniObserver, PredictsAWanderingRobotBetterThanNoModelAndTheTracker) {
  const testing::WanderingPlant plant;
  const testing::PlantRecording rec = testing::RecordWanderingPlant(plant, 60, 5);
  const OmniModel model = ResemblingModel(plant);
  const OmniReplayResult observed = ReplayOmniLog(model, rec.log, Options(OmniReplayState::kObserver));
  const OmniReplayResult tracked = ReplayOmniLog(model, rec.log, Options(OmniReplayState::kTracker));
  EXPECT_EQ(observed.state, "observer");
  EXPECT_EQ(tracked.state, "tracker");
  const double obs = PositionRmse(rec.log, observed);
  const double trk = PositionRmse(rec.log, tracked);
  const double cv = testing::ConstantVelocityRmse(rec.log, 4, 30);
  EXPECT_LT(obs, 0.8 * cv) << "observer " << obs << " m, constant velocity " << cv << " m";
  EXPECT_LT(obs, 0.65 * trk) << "observer " << obs << " m, tracker " << trk << " m";
  // An oracle that knows the robot's true velocity at the start and holds it (in the
  // robot's frame) bounds what any estimate from noisy poses can do; the observer comes
  // within 30 % of it.
  double sum = 0;
  int n = 0;
  for (std::size_t i = 30; i < rec.log.rows.size(); ++i) {
    if (!rec.log.rows[i].measured) continue;
    Pose2 p = rec.truth[i - 4];
    const Twist2 v = rec.velocity[i - 4];
    for (int k = 0; k < 40; ++k) {
      const double dt = 4 / plant.frame_rate / 40;
      p.x += dt * (std::cos(p.theta) * v.vx - std::sin(p.theta) * v.vy);
      p.y += dt * (std::sin(p.theta) * v.vx + std::cos(p.theta) * v.vy);
      p.theta += dt * v.omega;
    }
    sum += std::pow(p.x - rec.log.rows[i].pose.x, 2) + std::pow(p.y - rec.log.rows[i].pose.y, 2);
    ++n;
  }
  const double oracle = std::sqrt(sum / n);
  EXPECT_LT(obs, 1.3 * oracle) << "observer " << obs << " m, oracle " << oracle << " m";
}

// On the model itself with white velocity kicks of exactly the observer's process noise,
// a slip of its driving noise and camera noise of exactly R, the filter is consistent:
// its normalised innovations average the 3 degrees of freedom of a pose, and its
// velocity errors lie within the spread it claims.
TEST(OmniObserver, IsConsistentOnItsOwnModel) {
  OmniModel model = testing::Omni4();
  model.vision_noise_xy = 0.001;
  model.vision_noise_theta = 0.01;
  model.observer.process_noise = {0.3, 0.3, 2.0};
  model.driving_noise.sd = {0.1, 0.05, 0.4};
  model.driving_noise.correlation_time = 0.2;
  const double rate = 60;
  FrameTiming timing;
  timing.frame_rate = rate;
  timing.physics_substeps = DefaultPhysicsSubsteps(rate);
  FieldModel field;
  field.walls = false;
  std::unique_ptr<OmniBackend> truth = MakeOmniBackend("analytic", {model}, field, timing);
  OmniObserver observer(model, "analytic", rate);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  const int delay = model.command_delay_frames + model.vision_delay_frames;
  std::vector<Twist2> sent;
  double slip[3] = {0, 0, 0};
  const double a = std::exp(-1 / rate / model.driving_noise.correlation_time);
  int within = 0, counted = 0;
  for (int f = 0; f < 1800; ++f) {
    const double t = f / rate;
    const Twist2 command{1.0 * std::sin(0.7 * t), 0.8 * std::cos(0.45 * t), 2.0 * std::sin(0.3 * t)};
    sent.push_back(command);
    const Pose2 p = truth->pose(0);
    observer.AddFrame(Pose2{p.x + 0.001 * normal(rng), p.y + 0.001 * normal(rng), p.theta + 0.01 * normal(rng)},
                      command);
    if (f > 60) {
      const OmniEstimate e = observer.Estimate();
      const double err = e.velocity.vx - (truth->velocity(0).vx + slip[0]);
      const double spread = e.covariance(3, 3) + e.covariance(6, 6) + 2 * e.covariance(3, 6);
      within += std::abs(err) < 2 * std::sqrt(spread);
      ++counted;
    }
    truth->StepFrame({f - delay < 0 ? Twist2{} : sent[static_cast<std::size_t>(f - delay)]});
    // The slip moves the body on, unseen by the wheels, and wanders.
    Pose2 q = truth->pose(0);
    q.x += (std::cos(p.theta) * slip[0] - std::sin(p.theta) * slip[1]) / rate;
    q.y += (std::sin(p.theta) * slip[0] + std::cos(p.theta) * slip[1]) / rate;
    q.theta += slip[2] / rate;
    truth->MoveBody(0, q);
    for (int k = 0; k < 3; ++k)
      slip[k] = a * slip[k] + model.driving_noise.sd[static_cast<std::size_t>(k)] * std::sqrt(1 - a * a) * normal(rng);
    // White acceleration of the observer's density, as a velocity kick per frame.
    Twist2 v = truth->velocity(0);
    const double k = std::sqrt(1 / rate);
    v.vx += 0.3 * k * normal(rng);
    v.vy += 0.3 * k * normal(rng);
    v.omega += 2.0 * k * normal(rng);
    truth->SetVelocity(0, v);
  }
  const OmniInnovationStats& s = observer.innovations();
  EXPECT_EQ(s.refused, 0);
  const double mean_nis = s.nis_sum / s.updates;
  EXPECT_NEAR(mean_nis, 3.0, 0.5) << "over " << s.updates << " poses";
  // 95 % of a Gaussian lies within 2 sigma.
  EXPECT_NEAR(static_cast<double>(within) / counted, 0.95, 0.05);
}

// A camera that loses the robot for three seconds: the filter's spread grows through the
// gap, the first pose after it is taken, and the estimate is back on the robot within a
// quarter of a second.
TEST(OmniObserver, WidensThroughAVisionGapAndReacquires) {
  testing::WanderingPlant plant;
  plant.gap_start = 10;
  plant.gap_seconds = 3;
  const testing::PlantRecording rec = testing::RecordWanderingPlant(plant, 16, 8);
  OmniObserver observer(ResemblingModel(plant), "analytic", plant.frame_rate);
  std::vector<double> spread_in_gap;  // m, every half second of the gap
  double last_sd = 0;
  int gap_frames = 0, first_after = 0;
  for (std::size_t i = 0; i < rec.log.rows.size(); ++i) {
    const OmniLogRow& row = rec.log.rows[i];
    const bool taken = observer.AddFrame(row.measured ? std::optional<Pose2>(row.pose) : std::nullopt, row.command);
    const OmniEstimate e = observer.Estimate();
    const double sd = std::sqrt(e.covariance(0, 0) + e.covariance(1, 1));
    const double t = row.t;
    if (t >= 10 && t < 13) {
      ++gap_frames;
      if (gap_frames % 30 == 0) spread_in_gap.push_back(sd);
    }
    if (row.measured && i > 0 && rec.log.rows[i - 1].t < 13 && rec.log.rows[i - 1].t >= 12.9) {
      ++first_after;
      EXPECT_TRUE(taken) << "the first pose after the gap, t = " << t;
      EXPECT_GT(last_sd, 0.1) << "three seconds without the camera leave the position open";
    }
    if (t >= 13.25 && t < 13.5) {
      const Pose2& truth = rec.truth[i];
      EXPECT_LT(std::hypot(e.pose.x - truth.x, e.pose.y - truth.y), 0.01) << "t = " << t;
    }
    last_sd = sd;
  }
  EXPECT_EQ(gap_frames, 180);
  EXPECT_EQ(first_after, 1);
  ASSERT_EQ(spread_in_gap.size(), 6u);
  for (std::size_t k = 1; k < spread_in_gap.size(); ++k) EXPECT_GT(spread_in_gap[k], spread_in_gap[k - 1]) << k;
  EXPECT_EQ(observer.innovations().refused, 0);
}

// A pose far off is refused once; a robot carried away for good is re-acquired after
// the options' refusals in a row.
TEST(OmniObserver, RefusesAnOutlierAndReacquiresARobotCarriedAway) {
  const OmniModel model = testing::Omni4();
  OmniObserver observer(model, "analytic", 60);
  for (int f = 0; f < 30; ++f) observer.AddFrame(Pose2{0, 0, 0}, Twist2{});
  EXPECT_FALSE(observer.AddFrame(Pose2{1, 0, 0}, Twist2{}));
  EXPECT_NEAR(observer.Estimate().pose.x, 0, 1e-3);
  EXPECT_TRUE(observer.AddFrame(Pose2{0, 0, 0}, Twist2{}));
  for (int f = 0; f < 2; ++f) EXPECT_FALSE(observer.AddFrame(Pose2{2, 1, 0.5}, Twist2{}));
  observer.AddFrame(Pose2{2, 1, 0.5}, Twist2{});
  EXPECT_EQ(observer.innovations().restarts, 1);
  EXPECT_NEAR(observer.Estimate().pose.x, 2, 1e-9);
  EXPECT_TRUE(observer.AddFrame(Pose2{2, 1, 0.5}, Twist2{}));
  EXPECT_EQ(observer.innovations().refused, 4);
}

// Ahead of the estimate the pose spread grows with every frame, and predicting leaves
// the filter where it was.
TEST(OmniObserver, PredictionSpreadGrowsWithTheHorizonAndLeavesTheFilterUnchanged) {
  const testing::WanderingPlant plant;
  const testing::PlantRecording rec = testing::RecordWanderingPlant(plant, 3, 2);
  OmniObserver observer(ResemblingModel(plant), "analytic", plant.frame_rate);
  for (const OmniLogRow& row : rec.log.rows)
    observer.AddFrame(row.measured ? std::optional<Pose2>(row.pose) : std::nullopt, row.command);
  const OmniEstimate before = observer.Estimate();
  const OmniPrediction ahead = observer.PredictAhead(20, {}, true);
  ASSERT_EQ(ahead.pose.size(), 20u);
  ASSERT_EQ(ahead.pose_covariance.size(), 20u);
  for (std::size_t j = 1; j < 20; ++j) EXPECT_GT(ahead.pose_covariance[j](0, 0), ahead.pose_covariance[j - 1](0, 0));
  const OmniEstimate after = observer.Estimate();
  EXPECT_EQ(after.pose.x, before.pose.x);
  EXPECT_EQ(after.velocity.vy, before.velocity.vy);
  EXPECT_EQ(after.covariance, before.covariance);
  // Deterministic: the same prediction again, to the bit.
  EXPECT_EQ(observer.PredictAhead(20).pose.back().y, ahead.pose.back().y);
}

// Issue 64: a model's safeguard scales the predicted covariance k frames ahead by its
// scales at k (position rows and columns by one, the heading's by the other), and
// leaves the mean and the filter alone.
TEST(OmniObserver, TheIntervalsSafeguardScalesThePredictedCovarianceOnly) {
  const testing::WanderingPlant plant;
  const testing::PlantRecording rec = testing::RecordWanderingPlant(plant, 3, 2);
  OmniModel scaled = ResemblingModel(plant);
  scaled.observer.interval_scale = {{4, 2.0, 0.5}, {16, 1.5, 3.0}};
  OmniObserver plain(ResemblingModel(plant), "analytic", plant.frame_rate);
  OmniObserver safeguarded(scaled, "analytic", plant.frame_rate);
  for (const OmniLogRow& row : rec.log.rows) {
    const std::optional<Pose2> camera = row.measured ? std::optional<Pose2>(row.pose) : std::nullopt;
    plain.AddFrame(camera, row.command);
    safeguarded.AddFrame(camera, row.command);
  }
  const OmniPrediction a = plain.PredictAhead(20, {}, true);
  const OmniPrediction b = safeguarded.PredictAhead(20, {}, true);
  for (int k : {1, 4, 8, 16, 20}) {
    const std::size_t j = static_cast<std::size_t>(k - 1);
    const std::array<double, 2> s = scaled.observer.IntervalScaleAt(k);
    EXPECT_EQ(b.pose[j].x, a.pose[j].x);
    EXPECT_NEAR(b.pose_covariance[j](0, 0), s[0] * s[0] * a.pose_covariance[j](0, 0), 1e-15);
    EXPECT_NEAR(b.pose_covariance[j](0, 1), s[0] * s[0] * a.pose_covariance[j](0, 1), 1e-15);
    EXPECT_NEAR(b.pose_covariance[j](2, 2), s[1] * s[1] * a.pose_covariance[j](2, 2), 1e-15);
    EXPECT_NEAR(b.pose_covariance[j](0, 2), s[0] * s[1] * a.pose_covariance[j](0, 2), 1e-15);
  }
  EXPECT_EQ(safeguarded.Estimate().covariance, plain.Estimate().covariance);
}

// ODE and Bullet run the same filter, F from the model's analytic twin: their
// predictions of the wandering robot are as good as the analytic model's.
TEST(OmniObserver, RunsOnOdeAndBulletAsOnTheAnalyticModel) {
  const testing::WanderingPlant plant;
  const testing::PlantRecording rec = testing::RecordWanderingPlant(plant, 15, 3);
  const OmniModel model = ResemblingModel(plant);
  const double analytic = PositionRmse(rec.log, ReplayOmniLog(model, rec.log, Options(OmniReplayState::kObserver)));
  for (const std::string& engine : AvailableOmniBackends()) {
    if (engine == "analytic" || engine == "learned") continue;
    OmniReplayOptions o = Options(OmniReplayState::kObserver);
    o.backend = engine;
    const OmniReplayResult r = ReplayOmniLog(model, rec.log, o);
    EXPECT_EQ(r.state, "observer");
    EXPECT_NEAR(PositionRmse(rec.log, r), analytic, 0.15 * analytic) << engine;
  }
}

TEST(OmniObserver, RefusesBadInput) {
  const OmniModel model = testing::Omni4();
  OmniObserverOptions bad;
  bad.gate = 0;
  EXPECT_THROW(OmniObserver(model, "analytic", 60, bad), InputError);
  EXPECT_THROW(OmniObserver(model, "analytic", 0), InputError);
  EXPECT_THROW(OmniObserver(model, "no-such-engine", 60), InputError);
  OmniObserver observer(model, "analytic", 60);
  EXPECT_THROW(observer.PredictAhead(4), std::logic_error);
  EXPECT_THROW(observer.AddFrame(Pose2{std::nan(""), 0, 0}, Twist2{}), InputError);
  OmniReplayState state = OmniReplayState::kTracker;
  std::string why;
  EXPECT_FALSE(ParseOmniReplayState("kalman", &state, &why));
  EXPECT_NE(why.find("--state must be observer or tracker, got 'kalman'"), std::string::npos) << why;
  EXPECT_EQ(state, OmniReplayState::kTracker);  // untouched
  ASSERT_TRUE(ParseOmniReplayState("observer", &state, &why));
  EXPECT_EQ(state, OmniReplayState::kObserver);
}

}  // namespace
}  // namespace twinsim
