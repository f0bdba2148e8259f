// The state observer of an omni robot: an extended Kalman filter over the model's state,
// driven by the commands through the model's delay and corrected by each camera pose
// (docs/identification.md, "The observer"). Replay, compare, batch's scoring,
// identification and diagnosis predict from its estimate; a team's software can run it
// live, frame by frame, for the robot's state now and its pose K frames ahead.
//
// The model's whole state (pose, velocity, the controller's set-points and integrals,
// the effects' command queue and lags) lives in a Newtonian backend (analytic, ODE or
// Bullet), which the filter steps one camera frame at a time. Beside it the body slips:
// it moves at the model's velocity plus a slip d that the wheels, and so the on-board
// controller, do not see (the driving noise), a first-order Gauss-Markov process per
// robot axis of spread sigma_a and correlation time T (model.driving_noise), and, where
// the model has one, a slow slip b beside it, the same kind of process of spread
// sigma_b,a and correlation time T_b (driving_noise.drift: a run's own drift, which the
// filter learns over seconds of frames and carries far ahead). The filter's state is
//   s = (x, y, theta, vx, vy, omega, dx, dy, domega, bx, by, bomega): the pose in the
//   field frame, the model's velocity, the slip and the drift in the robot's,
// with its covariance P (the drift's rows and columns zero, and never computed, for a
// model without one). Per frame f (period dt, a = exp(-dt / T), a_b = exp(-dt / T_b)):
//   predict  the backend steps from f-1 to f under the command sent at f-1-D (D = the
//            model's command + vision delay, in frames: the filter runs at the camera's
//            capture time); the pose moves on by R(theta) (d + b) dt; d <- a d,
//            b <- a_b b. P <- F P F^T + Q
//            with F the frame's Jacobian: the pose block exactly (a turn of the start pose
//            swings the frame's displacement with it), the model velocity's columns by
//            finite differences of the model itself (on its analytic twin when the
//            backend is ODE or Bullet), the slip's and drift's as written. Q holds their
//            innovations sigma_a^2 (1 - a^2), sigma_b,a^2 (1 - a_b^2), and white acceleration of spectral density
//            q_a (model.observer.process_noise squared) on the model's velocity along
//            each robot axis a, integrated over the frame:
//              Q_a = q_a [dt^3/3 g g^T, dt^2/2 g e_a^T; dt^2/2 e_a g^T, dt e_a e_a^T],
//            g the axis in the field frame (forward, sideways) or the heading (turn).
//   update   with a camera pose z: nu = z - pose (heading wrapped), S = P_pp + R,
//            K = P H^T S^-1, s <- s + K nu, P <- (I - K H) P (I - K H)^T + K R K^T
//            (Joseph's form). The correction moves the backend's pose and velocity
//            (OmniBackend::MoveBody, SetVelocity); the controller and effects keep theirs.
//            A pose with nu^T S^-1 nu above the gate is refused as an outlier; after
//            `reacquire_after` refusals in a row the filter restarts on the camera (the
//            robot was carried away).
// A frame without a camera pose only predicts: P grows, and after a gap of seconds the
// next pose is taken with the weight the grown P gives it (the filter re-acquires).
// Predictions ahead carry the slip on, decaying as a^k, and the drift as a_b^k.
//
//   OmniObserver observer(model, "analytic", 1.0 / log.frame_period);
//   per frame:  observer.AddFrame(camera_pose_or_nullopt, command_sent_now);
//               OmniEstimate now = observer.Estimate();
//               OmniPrediction ahead = observer.PredictAhead(4);  // the pose 4 frames on
#pragma once

#include <Eigen/Core>
#include <array>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "robots/omni/omni_model.h"
#include "sim/omni_backend.h"

namespace twinsim {

struct OmniObserverOptions {
  // Refuse a camera pose whose normalised innovation squared exceeds this: a pose some
  // 14 standard deviations off, a misdetection rather than a robot the model does not
  // quite know (a model's error shows as innovations of 30 to 50 now and then, which the
  // filter must follow; chi-square with 3 degrees of freedom passes 30.7 once in 1e6).
  double gate = 200;
  int reacquire_after = 3;       // refusals in a row after which the filter restarts on the camera
  double initial_speed_sd = 1.0;  // m/s, the velocity's standard deviation at the start
  double initial_turn_sd = 5.0;   // rad/s
  // Finite-difference steps of the velocity columns of F: above an encoder count's speed.
  double speed_step = 0.02;  // m/s
  double turn_step = 0.2;    // rad/s
  // F's model-velocity columns are differenced anew every this many frames and reused
  // in between (they change with the controller's saturation, slowly against a frame).
  int jacobian_interval = 4;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// How a prediction's start state is estimated, and its words on the command line, in
// model and predictor files and in results, in the enumerators' order: the observer
// (this filter: pose, velocity and slip from every camera pose so far), or the open-loop
// tracker (the model moved to each measured pose, its velocity its own).
enum class OmniReplayState { kObserver, kTracker };
inline constexpr const char* kOmniReplayStateWords[] = {"observer", "tracker"};

// Its word: "observer", "tracker".
inline const char* OmniReplayStateName(OmniReplayState state) { return kOmniReplayStateWords[static_cast<int>(state)]; }

// The state a word names into *state; false for another word, saying why in *why, `what`
// ("--state") naming the option.
bool ParseOmniReplayState(const std::string& word, OmniReplayState* state, std::string* why,
                          const std::string& what = "--state");

inline constexpr int kObserverStates = 12;
// The states of a filter whose model has no drift (the first nine).
inline constexpr int kObserverStatesWithoutDrift = 9;
using ObserverMatrix = Eigen::Matrix<double, kObserverStates, kObserverStates>;

// The filter's estimate at its newest frame.
struct OmniEstimate {
  int frame = -1;         // frames since the first AddFrame (-1: not started)
  Pose2 pose;             // field frame
  Twist2 velocity;        // robot frame: the body's, the model's velocity plus the slip and drift
  Twist2 model_velocity;  // robot frame: the model's (what its wheels and controller see)
  Twist2 slip;            // robot frame: the slip
  Twist2 drift;           // robot frame: the slow slip (zero for a model without drift)
  // Of (x, y, theta, model vx, vy, omega, slip vx, vy, omega, drift vx, vy, omega).
  ObserverMatrix covariance = ObserverMatrix::Zero();
};

// The parts a predicted pose's covariance is the sum of (before the intervals'
// safeguard scales it): P_k = Phi P_0 Phi' + sum_j Phi_j Q_j Phi_j', Q split by the
// states it drives. kStartEstimate: the estimate's own uncertainty at the start, carried
// on; kProcessNoise: the model's process noise on its velocity (observer.process_noise);
// kDrivingNoise: the slip (driving_noise); kDrift: the slow slip (driving_noise.drift).
enum OmniCovariancePart { kStartEstimate, kProcessNoise, kDrivingNoise, kDrift, kCovarianceParts };
inline constexpr const char* kOmniCovariancePartNames[kCovarianceParts] = {"start estimate", "process noise",
                                                                            "driving noise", "drift"};
// The same as file keys (report.json, spread_budget.csv).
inline constexpr const char* kOmniCovariancePartKeys[kCovarianceParts] = {"start_estimate", "process_noise",
                                                                           "driving_noise", "drift"};
using OmniCovarianceParts = std::array<Eigen::Matrix3d, kCovarianceParts>;

// The poses of the frames ahead of the estimate, with their uncertainty.
struct OmniPrediction {
  std::vector<Pose2> pose;                      // frames 1..k ahead
  std::vector<Eigen::Matrix3d> pose_covariance;  // of (x, y, theta) per frame; empty unless asked for
  // With `parts`: per frame the covariance's parts (OmniCovariancePart), unscaled by
  // the model's intervals' safeguard; else empty.
  std::vector<OmniCovarianceParts> pose_covariance_parts;
  // With the covariance and the model's observer.seen_inputs: per frame the mean
  // distance of the frames so far from them (what the intervals' growth reads); else empty.
  std::vector<double> input_distance;
};

// Totals of the camera poses the filter has seen.
struct OmniInnovationStats {
  int updates = 0;            // poses taken
  int refused = 0;            // poses refused by the gate
  int restarts = 0;           // re-acquisitions after refusals in a row
  double nis_sum = 0;         // sum of nu^T S^-1 nu over the poses taken (3 per pose when consistent)
  double log_likelihood = 0;  // sum of log N(nu; 0, S) over the poses taken
  double last_nis = 0;
};

// Everything that changes inside an observer (OmniObserver::Save).
struct OmniObserverState {
  OmniBackendState backend;
  ObserverMatrix covariance = ObserverMatrix::Zero();
  Eigen::Vector3d slip = Eigen::Vector3d::Zero();
  Eigen::Vector3d drift = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 3> velocity_columns = Eigen::Matrix<double, 6, 3>::Zero();
  double jacobian_theta = 0;
  int frames_since_jacobian = -1;
  Twist2 last_acting;
  std::deque<Twist2> sent;
  bool started = false;
  int frame = -1;
  int refused_in_a_row = 0;
  OmniInnovationStats stats;
};

// The covariance of a camera pose (x, y, theta) as `model`'s observer takes it: its
// observer noise (OmniModel::ObserverNoiseXy, ObserverNoiseTheta) squared, uncorrelated.
Eigen::Matrix3d MeasurementCovariance(const OmniModel& model);

class OmniObserver {
 public:
  // A filter for one robot of `model` on `backend` (analytic, ode or bullet) at the
  // camera's `frame_rate` (Hz). Throws InputError for a backend without a velocity
  // state (learned: its window of measured poses is its own estimate), an unknown
  // backend or invalid options.
  OmniObserver(const OmniModel& model, const std::string& backend, double frame_rate,
               const OmniObserverOptions& options = {});
  // The same on a backend the caller has built for `model` alone (one robot, no walls):
  // the filter owns it from now on. Throws InputError as above.
  OmniObserver(const OmniModel& model, std::unique_ptr<OmniBackend> backend, const OmniObserverOptions& options = {});
  ~OmniObserver();
  OmniObserver(const OmniObserver&) = delete;
  OmniObserver& operator=(const OmniObserver&) = delete;

  // One camera frame: `camera` the pose captured in it (nullopt: none), `command` the
  // command sent in it (robot frame). The first frame with a pose starts the filter
  // there, at rest with a wide velocity. Returns true when the pose was taken.
  // Throws CheckFailed when the estimate stops being finite.
  bool AddFrame(const std::optional<Pose2>& camera, const Twist2& command);

  // The same one step at a time, for a caller that knows the command acting in each
  // frame (the residual predictors' track, learning/omni_residual.h, which passes the
  // commands after the model's delay itself): Start the filter at a pose moving at
  // `velocity` (robot frame; the model's velocity, no slip, the covariance of a start),
  // then per frame PredictFrame under the command acting over it (with `covariance`, P
  // propagated too) and, with a camera pose, CorrectFrame (true when the gate took it).
  // Throws as AddFrame does; std::logic_error before Start.
  void Start(const Pose2& pose, const Twist2& velocity);
  void PredictFrame(const Twist2& acting, bool covariance = true);
  bool CorrectFrame(const Pose2& camera);
  // Puts the estimate's pose at `pose` without a measurement (a predictor's own step):
  // its velocity, slip and covariance stay.
  void MovePose(const Pose2& pose);

  // The filter's whole state, to come back to (the backend's included).
  OmniObserverState Save() const;
  void Restore(const OmniObserverState& state);

  bool started() const { return started_; }
  // True when the model has a drift (the filter's state is then all kObserverStates).
  bool has_drift() const { return has_drift_; }
  int delay_frames() const { return delay_; }
  const OmniModel& model() const { return model_; }
  OmniEstimate Estimate() const;
  const OmniInnovationStats& innovations() const { return stats_; }
  // The covariance of a camera pose (x, y, theta) as the filter takes it.
  const Eigen::Matrix3d& measurement_covariance() const { return r_; }

  // The poses of the next k frames from the estimate, the filter unchanged: the commands
  // already sent act first, then `planned` (the commands to be sent from the next frame
  // on), then the last of them held. With `covariance`, each pose's covariance too (the
  // filter's prediction, process noise included). Throws std::logic_error before start.
  // With `parts` (implies `covariance`), the covariance's parts too.
  OmniPrediction PredictAhead(int k, const std::vector<Twist2>& planned = {}, bool covariance = false,
                              bool parts = false);

  // The newest frame's input (robots/omni/omni_seen_inputs.h): the wheel speeds of the
  // command that acted in it and of the body's estimated velocity.
  Eigen::VectorXd InputFeature() const;
  // The backend the filter steps (for tests; its state is the estimate).
  const OmniBackend& backend() const { return *backend_; }

 private:
  // One frame under the command acting now; with `jacobian`, P is propagated too.
  void Step(const Twist2& acting, bool jacobian);
  // P over the frame from pose p0 (velocity v0, acceleration in m/s^2) to `moved`, F's
  // velocity columns those last differenced (`difference`: in this frame).
  // c, sn: cos and sin of p0.theta.
  void Propagate(const Pose2& p0, double c, double sn, const Pose2& moved, bool difference, const Twist2& v0,
                 double acceleration);
  // What moves the body unseen by the wheels: the slip, and the drift where the model has one.
  Eigen::Vector3d Unseen() const { return has_drift_ ? Eigen::Vector3d(slip_ + drift_) : slip_; }
  // Q of one frame at heading theta (rad), the model's translational speed (m/s),
  // acceleration over the frame (m/s^2) and turn rate (rad/s).
  ObserverMatrix ProcessNoise(double theta, double speed, double acceleration, double turn_rate) const;
  ObserverMatrix InitialCovariance() const;
  void Restart(const Pose2& pose, const Twist2& velocity);
  // The filter started at `pose` moving at `velocity`: the covariance of a start, no slip.
  void Begin(const Pose2& pose, const Twist2& velocity);
  // One frame under `acting` (Step), then the divergence check.
  void Advance(const Twist2& acting, bool covariance);
  Twist2 Acting(int ahead, const std::vector<Twist2>& planned) const;

  OmniModel model_;
  OmniObserverOptions options_;
  double dt_ = 0;
  int delay_ = 0;
  std::unique_ptr<OmniBackend> backend_;
  std::unique_ptr<OmniBackend> twin_;  // analytic, for F's velocity columns; null when backend_ is analytic
  std::deque<Twist2> sent_;            // the last delay_ + 1 commands sent, the newest last
  ObserverMatrix p_ = ObserverMatrix::Zero();
  Eigen::Matrix<double, 6, 3> velocity_columns_ = Eigen::Matrix<double, 6, 3>::Zero();  // F's, last differenced
  double jacobian_theta_ = 0;       // rad, the heading they were differenced at
  int frames_since_jacobian_ = -1;  // -1: none yet
  Eigen::Vector3d slip_ = Eigen::Vector3d::Zero();  // d, robot frame
  Eigen::Vector3d drift_ = Eigen::Vector3d::Zero();  // b, robot frame
  Eigen::MatrixXd wheels_from_body_;                // J, for InputFeature
  Twist2 last_acting_;                              // the command of the newest frame's step
  double slip_decay_ = 0;                           // a
  double drift_decay_ = 0;                          // a_b
  bool has_drift_ = false;
  Eigen::Matrix3d r_ = Eigen::Matrix3d::Zero();
  bool started_ = false;
  int frame_ = -1;
  int refused_in_a_row_ = 0;
  OmniInnovationStats stats_;
  // While PredictAhead splits the covariance: its parts, propagated beside p_.
  std::array<ObserverMatrix, kCovarianceParts>* parts_ = nullptr;
};

}  // namespace twinsim
