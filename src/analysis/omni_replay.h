// Replaying a measured omni log through a model (`twinsim replay`, CONTRACT.md).
//
// Row i of the result is the model's prediction of frame i made from the measured
// state K frames earlier and the logged commands since, delayed by the model's command
// + vision delay D: the step from frame j to j+1 is driven by the command logged at
// frame j - D. K = 0 is one free run from the first row.
//
// The state at the start frame S = i - K is estimated from the measurements up to S:
//   - "observer" (the default on the Newtonian backends): the model's Kalman filter
//     (estimation/omni_observer.h) runs along the log under the logged commands and
//     corrects pose and velocity at every row with a new measurement; the controller's
//     and the effects' states are the model's own under that estimate;
//   - "tracker" (the only one on the learned backend, whose window of measured poses is
//     its own estimate; kept on the others for comparison): the model runs along the
//     log under the logged commands and only its pose is corrected to each measurement
//     (OmniBackend::MoveBody), so its velocity is the commands' open-loop response.
// Frames without a new measurement (OmniLogRow::measured) leave either to its own
// prediction. Each prediction runs K frames from the estimate, which is then restored.
// Commands before the log's first row are taken as zero; a row is predicted once the
// estimate has run kWarmUpFrames; earlier rows, and rows without a row at S, hold the
// measured pose.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "backends/omni_backend_factory.h"
#include "core/pose.h"
#include "estimation/omni_observer.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

inline constexpr int kWarmUpFrames = 15;

struct OmniReplayOptions {
  std::string backend = "ode";
  OmniBackendOptions backend_options;  // the predictor, for the learned backend
  int horizon = 4;  // K, frames; 0 = free run
  int stride = 1;   // predict from every stride-th frame only (1: every row), for fits that need speed
  // Where the stride counts from: -1, the end of the estimate's warm-up (which depends on
  // the model's delay for the tracker); a frame index, the same frames for every model
  // (scores that compare models on the same rows).
  int stride_origin = -1;
  // Where set, how many frames ahead the prediction from each frame on the stride (its
  // index from the log's first frame) must reach: none where 0, only the horizons up to
  // it (K and `also`) where less than K. Fits that score some blocks only predict nothing
  // they throw away. The tracker predicts all K wherever it is not 0. Without
  // `features`, the observer's filter stops at the last frame `reach` names (`grip`
  // counts the steps until then; a divergence after it goes unseen).
  std::function<int(int)> reach;
  // How the start state is estimated (see above). The learned backend always uses the
  // tracker.
  OmniReplayState state = OmniReplayState::kObserver;
  OmniObserverOptions observer;
  // With samples N > 0 (K >= 1), N draws of each predicted pose, from a stream seeded by
  // `seed`. The observer's state: from the filter's prediction K frames ahead, its mean
  // and covariance (the estimate's own uncertainty carried on, the driving noise and the
  // model's process noise added; estimation/omni_observer.h). The tracker's (the learned
  // backend's): N rollouts of the backend from the start, each moved on by a draw of the
  // driving noise (robots/omni/omni_driving_noise.h), the predictor's own where it has
  // one (analysis/learned_noise.h), else the model's; their covariance about the
  // prediction is the row's covariance.
  int samples = 0;
  std::uint64_t seed = 1;
  // With covariance (K >= 1; the tracker only with samples): each predicted row's pose
  // covariance too (OmniReplayResult::covariance), the prediction's as the samples draw
  // from it.
  bool covariance = false;
  // With covariance, on the observer's state: each predicted row's covariance split into
  // its parts too (OmniReplayResult::covariance_parts).
  bool covariance_parts = false;
  // Shorter horizons (each 1..K-1) predicted from the same start frames: one K-frame
  // prediction gives them all (OmniReplayResult::also, in this order).
  std::vector<int> also;
  // The parameters' own uncertainty: the model moved either way along each direction of
  // its parameters' covariance (ParameterShiftedModels,
  // identification_omni/omni_identification.h). With the covariance or samples on the
  // observer's state, each is replayed alike (its mean only), and each predicted row's
  // covariance gains the parameters' part, sum_l d_l d_l^T, d_l half the difference of
  // pair l's predictions (OmniReplayResult::parameter_covariance; not scaled by the
  // model's intervals' safeguard, which was fitted without it). Empty: none. They are
  // replayed on `parameter_backend` ("": `backend`): the engine the covariance was
  // fitted on, where the other engines' replays would cost an engine's time for a
  // second-order difference.
  std::vector<std::array<OmniModel, 2>> parameter_shifts;
  std::string parameter_backend;
  // The tracker's samples (the learned backend's): each rollout first draws the
  // backend's parameters from their own uncertainty (OmniBackend::DrawParameters: a
  // linear predictor's weights, docs/learning.md "The weights' own uncertainty", or one
  // of a network's ensemble), where
  // its model carries one; the prediction itself stays the estimate's.
  bool parameter_draws = true;
  // The observer's state (K >= 1; `reach` 0 predicts nothing): each row's input
  // (OmniObserver::InputFeature) after its frame, into OmniReplayResult::input_feature
  // (the seen inputs of identify's fit), and the estimate's body velocity into
  // OmniReplayResult::estimated_velocity (identify's report plots it).
  bool features = false;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
  // True when a prediction starts at `frame`, `since_warm_up` frames after the warm-up.
  bool OnStride(int frame, int since_warm_up) const;
};

struct OmniReplayResult {
  std::vector<double> t;             // s, one per log row
  std::vector<Pose2> pose;           // predicted (or held measured) pose per row
  std::vector<bool> predicted;       // false where the measured pose was held
  int delay_frames = 0;              // D used
  // The state estimate used: "observer" or "tracker" (OmniReplayStateName); "none" for a
  // free run, a baseline's name for a baseline (analysis/omni_baselines.h).
  std::string state;
  // Learned backend: steps on which the predictor was held to the bounds of its training
  // data (it left what it learned); the user is told.
  long bounded_steps = 0;
  // Learned backend: steps whose inputs lay beyond anything in its training data
  // (InputsSeen): its predictions there are extrapolation; the user is told.
  long unseen_input_steps = 0;
  // Physics: the analytic engine's check of its own validity over every step simulated
  // (the tracking and every prediction): where a wheel needed more grip than it has, a
  // real robot slips and the analytic model does not (engines/omni_engine.h).
  GripCheck grip;
  // With OmniReplayOptions::samples N: per row N poses, the draws where the row was
  // predicted, else N copies of the held measured pose; empty otherwise.
  std::vector<std::vector<Pose2>> samples;
  // With OmniReplayOptions::covariance or samples: per row the covariance of the
  // predicted pose (x, y, theta), zero where the measured pose was held; and the camera
  // pose's own covariance as the filter takes it (a measurement's distribution is the
  // prediction's plus this).
  std::vector<Eigen::Matrix3d> covariance;
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
  // With OmniReplayOptions::covariance_parts: per row the covariance's parts
  // (estimation/omni_observer.h's OmniCovariancePart), zero where not predicted; their sum
  // is the covariance before the model's intervals' safeguard scales it.
  std::vector<OmniCovarianceParts> covariance_parts;
  // With OmniReplayOptions::parameter_shifts (and the covariance or samples on the
  // observer's state): per row the parameters' part of `covariance` (included there),
  // zero where not predicted; else empty.
  std::vector<Eigen::Matrix3d> parameter_covariance;
  // How many draws each row's covariance was estimated from (the samples' mean square
  // about the prediction); 0: it is the filter's own, known (the observer's).
  int covariance_draws = 0;
  // With the covariance and a model with observer.seen_inputs: per row its prediction's
  // mean distance from them (OmniPrediction::input_distance); on the learned backend with
  // a predictor that knows its training ranges, how far beyond them the prediction's own
  // steps' inputs went at most (OmniBackend::TakeInputExcess); 0 where not predicted;
  // else empty.
  std::vector<double> input_distance;
  // With OmniReplayOptions::features: per row its frame's input (empty before the
  // observer started) and the estimate's body velocity after the frame (robot frame,
  // the model's plus the slip and drift; zero before the start); else empty.
  std::vector<Eigen::VectorXd> input_feature;
  std::vector<Twist2> estimated_velocity;
  // With OmniReplayOptions::also: one result per shorter horizon, in its order (the same
  // fields; their own `also` empty).
  std::vector<OmniReplayResult> also;
  int num_predicted() const;
};

// A result that predicts nothing yet: every row holds its measured pose, none marked.
OmniReplayResult HeldMeasurements(const OmniLog& log);

// True when row i of `result` is a prediction and the log holds a measurement there:
// the rows every score of a replay is taken over.
inline bool PredictedAndMeasured(const OmniLog& log, const OmniReplayResult& result, std::size_t i) {
  return result.predicted[i] && log.rows[i].measured;
}

// Root-mean-square distance (m) between the predicted rows and the log's poses, over
// the rows with a measurement.
double PositionRmse(const OmniLog& log, const OmniReplayResult& result);

// The prediction errors of a replay, per predicted row that holds a measurement: the
// measured pose minus the predicted one as (forward, sideways) in the measured robot
// frame and the heading error times `radius` (a point on the rim), all in metres.
struct OmniPoseErrors {
  std::vector<std::size_t> rows;         // log rows
  std::vector<std::array<double, 3>> e;  // m, one per row above
};
OmniPoseErrors PoseErrorsInRobotFrame(const OmniLog& log, const OmniReplayResult& result, double radius);

// Throws InputError for an unknown backend; CheckFailed if the model diverges.
OmniReplayResult ReplayOmniLog(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                               const std::function<void(int, int)>& progress = {});

// The model's free run over the rows [first_row, last_row) of `log`, started from the
// state estimated at first_row (the estimate runs from the log's start as above).
// Rows outside the stretch hold the measured pose and are not marked predicted. Throws
// as ReplayOmniLog; InputError when first_row is before the estimate's warm-up ends.
OmniReplayResult ReplayOmniStretch(const OmniModel& model, const OmniLog& log, const OmniReplayOptions& options,
                                   std::size_t first_row, std::size_t last_row);

}  // namespace twinsim
