// Learning the robot's 18 on-board PID parameters by driving test runs (seed 000,
// sections 1.1 and 3): the robot knows nothing of its own mechanics; it only drives the
// seed's test run with candidate controller settings and scores what the camera saw.
//
// The test run (a scene whose robot drives a `test_drive` command): from rest,
// accelerate at `direction_deg` to the heading, drive `drive_time` seconds without
// turning, then command zero (stop hard) and wait until the scene ends. Its quality is
//   Q = w_d distance - w_dev deviation - w_rot rotation - w_stop stop_distance
// where, in the camera's frames (re-timed to when they were captured),
//   distance       m, the run along the intended direction until the stop command acts,
//   deviation      m, the largest distance from the intended line during the run,
//   rotation       rad, the largest heading change from the start during the run (the
//                  sum of |dtheta| over frames would mostly add up camera noise),
//   stop_distance  m, from where the stop command acts to where the robot comes to rest.
// Also reported: avg_speed = distance / drive_time (m/s), and end_deviation_pct, the
// end point's distance from the intended line in percent of the distance it ran.
//
// The parameter vector is [forward, sideways, rotation] x [kp, ki, kd, integral_limit,
// output_limit, slew_rate] (PidGains::AsVector order). TunePid() runs the policy
// gradient search (tuning/policy_gradient.h) over it, scoring each iteration's sets
// in parallel, deterministically for a given seed.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim/omni_simulation.h"
#include "tuning/policy_gradient.h"

namespace twinsim {

inline constexpr int kPidParameters = 18;

// "forward.kp", ..., "rotation.slew_rate", in parameter-vector order.
std::vector<std::string> PidParameterNames();
// The 18 parameters of a controller, and a controller with them set.
Eigen::VectorXd PidParameters(const OmniControllerModel& controller);
OmniControllerModel WithPidParameters(OmniControllerModel controller, const Eigen::VectorXd& p);

// The default weights make driving worth twice the distance it takes to stop: with
// equal weights a robot with weak gains, which stops as slowly as it starts, scores
// no better than one standing still, and learning from zeros has nothing to climb.
struct QualityWeights {
  double distance = 1;         // per m
  double deviation = 0.5;      // per m
  double rotation = 0.25;      // per rad
  double stop_distance = 0.5;  // per m
};

struct TestRunScore {
  double quality = 0;
  double distance = 0;           // m
  double deviation = 0;          // m
  double rotation = 0;           // rad, largest |theta - theta_0|
  double stop_distance = 0;      // m
  double avg_speed = 0;          // m/s
  double end_deviation_pct = 0;  // percent of the distance run
  std::string failure;           // non-empty: the run diverged (and where); quality is then kFailedQuality
};

// The quality a run that diverged gets: worse than any run that stayed put.
inline constexpr double kFailedQuality = -10;

// What the test run is, from the scene's robot and its `test_drive` commands.
struct TestDrive {
  double start = 0.5;       // s at rest before the drive
  double drive_time = 1.5;  // s
  double direction = 0;     // rad, relative to the start heading
  double duration = 4;      // s, the whole run (the scene's duration)
  double frame_rate = 30;   // Hz
  int command_delay_frames = 2;
  int vision_delay_frames = 2;
};

// Scores one robot's frames of a test run. Throws InputError when no frame was
// observed (the scene drops them all).
TestRunScore ScoreTestRun(const std::vector<FrameRecord>& frames, const TestDrive& drive,
                          const QualityWeights& weights);

// Runs test drives of one scene with any controller parameters; thread-safe (every
// call builds its own simulation).
class TestRunEvaluator {
 public:
  // Throws InputError when the scene is not a test run: exactly one robot, driven by
  // `test_drive`, with at least 0.5 s after the stop command.
  TestRunEvaluator(Scene scene, std::string backend, QualityWeights weights);
  TestRunScore Evaluate(const Eigen::VectorXd& parameters) const;
  // Runs the scene with `parameters` and returns the robot's frames (for plots).
  std::vector<FrameRecord> Frames(const Eigen::VectorXd& parameters) const;
  // Scores many sets in parallel (threads: 0 = one per core); results in order.
  std::vector<TestRunScore> EvaluateAll(const std::vector<Eigen::VectorXd>& sets, int threads) const;

  const Scene& scene() const { return scene_; }
  const std::string& backend() const { return backend_; }
  const TestDrive& drive() const { return drive_; }
  const QualityWeights& weights() const { return weights_; }

 private:
  Scene scene_;
  std::string backend_;
  QualityWeights weights_;
  TestDrive drive_;
};

struct PidTuningOptions {
  std::string start = "model";           // "model": the model's controller; "zeros": all 18 at zero
  std::array<bool, 3> learn = {true, true, true};  // forward, sideways, rotation
  int iterations = 10;
  int sets_per_iteration = 20;
  double exponent = 1;                   // x of eq. 5
  int patience = 0;                      // see PolicyGradientOptions
  double epsilon = 0.25;                 // perturbation, as a fraction of each parameter's scale
  double eta = 0.25;                     // step, as a fraction of each parameter's scale
  Eigen::VectorXd scale;                 // 18, the size of each parameter (default: DefaultPidScale())
  double upper = 10;                     // each parameter is kept in [0, upper x scale]
  QualityWeights weights;
  int threads = 0;                       // 0: one per core; results do not depend on it
  std::uint64_t seed = 1;

  bool IsValid(std::string* why) const;
};

// Reads the scene's `tune_pid:` block (docs/pid_tuning.md) over the defaults; the seed
// is the scene's. Throws InputError with "path:line:col: ..." for every problem.
PidTuningOptions ReadPidTuningOptions(const Scene& scene);

// The size of each parameter: the hand-tuned defaults (docs/models.md), with a small
// derivative gain where the default has none.
Eigen::VectorXd DefaultPidScale();

struct PidTuningIteration {
  int iteration = 0;
  Eigen::VectorXd parameters;       // 18, the current set
  TestRunScore score;               // the current set's own test run
  std::vector<TestRunScore> tested; // every perturbed set's test run
};

struct PidTuningResult {
  std::vector<PidTuningIteration> iterations;
  PolicyGradientSummary search;
  Eigen::VectorXd start_parameters;  // 18
  Eigen::VectorXd best_parameters;   // 18, the best current set
  TestRunScore best_score;
  int test_runs = 0;
};

// Learns the parameters of the evaluator's scene. `on_iteration` sees every iteration
// as it finishes (progress). Throws InputError for invalid options.
PidTuningResult TunePid(const TestRunEvaluator& evaluator, const PidTuningOptions& options,
                        const std::function<void(const PidTuningIteration&)>& on_iteration = {});

}  // namespace twinsim
