// The simulation loop: it owns simulated time and the delay loop.
//
// Per camera frame k (t_k = k / frame_rate), for every robot:
//   1. the camera captures the true pose (plus Gaussian noise; the frame may be lost);
//   2. the capture enters the vision delay line and the one from frame
//      k - vision_delay_frames comes out to the behaviour;
//   3. the behaviour sends command c_k, which is logged with that observation;
//   4. c_k enters the command delay line and c_{k - command_delay_frames} comes out;
//   5. the backend advances one frame with the delayed commands.
// So a command logged in row k first moves the observed pose in row k + D + 1, with
// D = command + vision delay (four frames by default). Backends never see a delay.
//
// The model (robots, timing) is fixed at construction; SimulationState holds all that
// changes, and Save()/Restore() make a run repeatable from any frame.
//
// Robots off the field (SimRobot::present false, Remove(); Add() brings one back): the
// backends and the ball's engines keep a fixed number of robots, so a robot off the
// field is parked: held at rest at a spot of its own far outside any field
// (ParkedPose(), reset there after every frame), and in the ball's world further still,
// beyond where the ball counts as diverged, so nothing on the field can touch it. The
// camera captures nothing of it (its noise is still drawn: the other robots' streams
// stay), its commands and ball commands are replaced by zero, its behaviour is not
// asked, and its records say present = false.
//
// Moves by force (PullRobot(), PullBall()): for the frames that follow, the robot's
// delayed commands are replaced by a position controller's (towards the target, at
// most kPullSpeed and kPullAccel, kPullOmega), and the ball feels a critically damped
// pull (sim/ball_field.h), until each is within tolerance of its target or
// kPullTimeout has passed; both collide on the way like any robot and ball.
#pragma once

#include <cstdint>
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/delay_line.h"
#include "core/rng.h"
#include "sim/ball_field.h"
#include "sim/behaviour.h"
#include "sim/omni_backend.h"

namespace twinsim {

struct SimRobot {
  std::string name;
  OmniModel model;
  Pose2 start;
  std::unique_ptr<CommandSource> commands;
  bool present = true;  // on the field at the start (false: parked until Add())
};

// One row of what happened to one robot in one frame.
struct FrameRecord {
  double t = 0;            // s
  bool observed = false;   // false: this frame's observation was lost (not logged)
  Pose2 seen;              // what the observer received at t (captured D_v frames earlier)
  double stamp = 0;        // s, the time the observer logs for the frame: t off by the camera's jitter
  Twist2 command;          // sent at t, robot frame
  BallCommand ball_command;  // sent at t with it: kick, dribbler (zero without a ball)
  Pose2 truth;             // the true pose at t
  Twist2 truth_velocity;   // robot frame, true
  bool present = true;     // false: off the field this frame (truth is its parking spot)
};

// One frame of the ball: its true state at t, and where the camera saw it (captured
// the first robot's vision_frames earlier, with the ball's camera noise).
struct BallRecord {
  double t = 0;           // s
  BallState truth;        // field frame
  bool observed = false;  // false in the first frames, before any capture has arrived, and in lost frames
  Eigen::Vector3d seen = Eigen::Vector3d::Zero();  // m, the ball's centre as delivered at t
};

struct SimulationResult {
  std::string backend;                      // OmniBackend::name(): "ode", or "mixed: ode (a), analytic (b)"
  std::vector<std::string> robot_backends;  // per robot, the backend it ran on (OmniBackend::robot_backend)
  FrameTiming timing;
  std::vector<std::string> robot_names;
  std::vector<std::vector<FrameRecord>> frames;  // [robot][frame]
  std::vector<BallRecord> ball;                  // [frame]; empty without a ball
  GripCheck grip;  // the analytic engine's check of its validity over the run (engines/omni_engine.h)
};

// A robot being moved by force: where to, and how many frames are left before the
// pull gives up.
struct RobotPull {
  Pose2 target;         // field frame
  int frames_left = 0;
};

// A camera's noise on one robot's pose (standard deviations).
struct VisionNoise {
  double xy = 0;     // m, of x and of y
  double theta = 0;  // rad
};

// One camera's capture of one robot, drawn from `rng` in this order (run's camera and
// each of serve's cameras draw it alike, so a team's software sees from `serve` the
// camera `run` records): Gaussian noise on x, y and theta; a lost detection with the
// model's vision_drop_probability; where the model asks for it (a draw only then), its
// last captured pose sent again with vision_repeat_probability (*last holds the pose
// captured, repeated or not).
struct RobotCapture {
  Pose2 pose;
  bool lost = false;
};
RobotCapture CaptureRobot(const Pose2& truth, const VisionNoise& noise, const OmniModel& model, Rng* rng,
                          std::optional<Pose2>* last);
// How far a frame's time stamp is off the frame clock: uniform within the model's
// vision_time_jitter (a draw only where it has one), else 0.
double StampJitter(double vision_time_jitter, Rng* rng);

struct SimulationState {
  int frame = 0;
  std::vector<bool> present;                   // per robot: on the field
  std::vector<std::optional<RobotPull>> pulls;  // per robot: a move by force under way
  Rng rng;
  std::vector<DelayLine<Twist2>> commands_in_flight;                // per robot
  std::vector<DelayLine<std::optional<Pose2>>> captures_in_flight;  // per robot
  std::vector<std::optional<Pose2>> last_captured;                  // per robot, what the camera repeats
  std::vector<std::vector<Observation>> delivered;                  // per robot, recent window
  // Per robot, the true state of the last frame that passed the divergence check
  // (t, truth, truth_velocity only): what a divergence message reports as last good.
  std::vector<FrameRecord> last_good;
  OmniBackendState backend;
  // The ball (none without one): its field, its commands in flight per robot (each
  // robot's command delay) and its captures in flight (the camera's vision delay).
  std::optional<BallFieldState> ball;
  std::vector<DelayLine<BallCommand>> ball_commands_in_flight;
  std::optional<DelayLine<std::optional<Eigen::Vector3d>>> ball_captures_in_flight;
  Rng ball_rng;  // the ball camera's noise and lost frames
  // The camera's settings now: per robot its pose noise (the model's until a live
  // configuration changes it, SetVisionNoise), and how it sees the ball (SetBallVision).
  std::vector<VisionNoise> vision_noise;
  BallVision ball_vision;
  // Driving noise (OmniDrivingNoise::simulated): per robot the slip now (forward and
  // sideways m/s, turn rad/s, robot frame), drawn from a stream of its own so that the
  // camera's draws stay as they were.
  std::vector<std::array<double, 3>> slip;
  // And its drift (OmniDrivingNoise::drift), drawn at the robot's first slip.
  std::vector<std::array<double, 3>> drift;
  std::vector<char> drift_started;
  Rng drive_rng;
  BallRecord ball_record;  // the open (or last) frame's
  // Per robot, a copy of its behaviour as it was (null: none); filled by Save() only.
  std::vector<std::shared_ptr<const CommandSource>> behaviours;
};

class Simulation {
 public:
  // A move by force (PullRobot): the controller's speed limits, its time constant, and
  // when it lets go.
  static constexpr double kPullSpeed = 2;        // m/s
  static constexpr double kPullAccel = 3;        // m/s^2, braking towards the target
  static constexpr double kPullOmega = 4;        // rad/s
  static constexpr double kPullTau = 0.2;        // s, the position error's time constant
  static constexpr double kPullTolerance = 0.01;  // m; arrived within this and kPullAngleTolerance
  static constexpr double kPullAngleTolerance = 0.02;  // rad
  static constexpr double kPullTimeout = 10;     // s, a pull that has not arrived by then stops

  // Places every robot at rest at its start; commands before t = 0 are zero and the
  // observer has seen the robots standing at their starts.
  Simulation(std::vector<SimRobot> robots, std::unique_ptr<OmniBackend> backend, std::uint64_t seed);

  int frame() const { return state_.frame; }
  double time() const { return state_.frame * backend_->timing().frame_dt(); }
  const OmniBackend& backend() const { return *backend_; }
  int num_robots() const { return static_cast<int>(robots_.size()); }

  // Runs one frame and returns each robot's record of it. Throws CheckFailed when a
  // robot's state becomes non-finite or runs away, naming the robot, time and value
  // and giving the robot's last good state (the frame before).
  std::vector<FrameRecord> Step();

  // A frame in two halves, for a loop whose commands come from outside the process
  // (twinsim serve, serve/live_field.h): BeginFrame() runs steps 1-2 above and returns
  // each robot's record without its command; EndFrame() sends records[i].command
  // (robot frame) for robot i and runs steps 4-5. Step() is BeginFrame, each robot's
  // CommandSource, EndFrame. EndFrame throws CheckFailed for a non-finite command and
  // std::logic_error when no frame was begun; BeginFrame and Step throw std::logic_error
  // while a frame is open.
  std::vector<FrameRecord> BeginFrame();
  void EndFrame(std::vector<FrameRecord>* records);
  // EndFrame with what each robot does to the ball (kicks, dribbler; one per robot,
  // delayed by the robot's command delay like its move). Throws std::invalid_argument
  // for a list of another length, and as EndFrame.
  void EndFrame(std::vector<FrameRecord>* records, const std::vector<BallCommand>& ball_commands);

  // Puts a ball on the field (docs/ball.md) at `start`, before the first frame; the
  // camera sees it with the first robot's vision delay, and with `vision`'s noise and
  // lost frames (drawn from a stream of their own: the robots' noise stays as it was). Throws std::logic_error after
  // the first frame and std::invalid_argument for a field of other robots.
  void AddBall(std::unique_ptr<BallField> ball, const BallState& start, const BallVision& vision = {});
  bool has_ball() const { return ball_ != nullptr; }
  // The ball's field (null without one).
  const BallField* ball() const { return ball_.get(); }
  // The ball's record of the open frame (or the last one): its true state now and what
  // the camera delivers now. Throws std::logic_error without a ball.
  const BallRecord& ball_record() const;
  // Puts the ball at `state` now (a referee's hand; the captures in flight stay).
  // Throws std::logic_error without a ball.
  void TeleportBall(const BallState& state);
  // What robot i's own CommandSource sends in the open frame (zero without one), for a
  // loop that drives some robots from outside and the others by their sources. Throws
  // std::logic_error when no frame is open.
  Twist2 SourceCommand(int robot);
  // What robot i's own CommandSource does to the ball in the open frame (none without
  // one); ask after SourceCommand. Throws as SourceCommand.
  BallCommand SourceBallCommand(int robot);
  // The observations delivered to robot i so far (the newest kObservationWindow, oldest
  // first).
  const std::vector<Observation>& delivered(int robot) const {
    return state_.delivered.at(static_cast<std::size_t>(robot));
  }
  // Puts robot i at `pose` moving at `velocity` (robot frame) now, as a referee's hand
  // would: the commands and captures already in flight stay in flight; a move by force
  // under way ends. Throws std::logic_error for a robot off the field (Add it).
  void Teleport(int robot, const Pose2& pose, const Twist2& velocity);
  // Robot i's camera noise now, and a change of it (standard deviations: m of x and y,
  // rad of theta), as a live configuration makes (twinsim serve's SimulatorConfig): a
  // change of the state, so Save() keeps it and Restore() puts the saved one back; the
  // robot's model (and what its observer assumes) stays. Throws std::invalid_argument for
  // a negative or non-finite value.
  const VisionNoise& vision_noise(int robot) const { return state_.vision_noise.at(static_cast<std::size_t>(robot)); }
  void SetVisionNoise(int robot, double xy, double theta);
  // How the camera sees the ball, and a change of it, in the state as SetVisionNoise's.
  // Throws std::logic_error without a ball and std::invalid_argument for a negative or
  // non-finite value or a probability over 1.
  const BallVision& ball_vision() const { return state_.ball_vision; }
  void SetBallVision(const BallVision& vision);
  // Whether robot i is on the field now.
  bool present(int robot) const { return state_.present.at(static_cast<std::size_t>(robot)); }
  // Takes robot i off the field now (parks it, see above); a move by force it was under
  // ends. Its captures already in flight still arrive, as a teleport's would. Nothing
  // happens for a robot already off.
  void Remove(int robot);
  // Puts robot i on the field now (or, if it is on, teleports it) at `pose` moving at
  // `velocity` (robot frame).
  void Add(int robot, const Pose2& pose, const Twist2& velocity);
  // Where robot i is parked while off the field (field frame): 500 m out, 2 m apart.
  static Pose2 ParkedPose(int robot);
  // Starts moving robot i by force towards `target` (replacing a move under way); throws
  // std::logic_error for a robot off the field. pull(i) is the move under way, if any.
  void PullRobot(int robot, const Pose2& target);
  const std::optional<RobotPull>& pull(int robot) const { return state_.pulls.at(static_cast<std::size_t>(robot)); }
  // Starts moving the ball by force towards `target` (x, y on the floor; BallField::Pull).
  // Throws std::logic_error without a ball.
  void PullBall(const Eigen::Vector2d& target);
  const std::string& robot_name(int robot) const { return robots_.at(static_cast<std::size_t>(robot)).name; }
  const OmniModel& robot_model(int robot) const { return robots_.at(static_cast<std::size_t>(robot)).model; }

  // Runs `frames` frames; `progress(done, total)` is called now and then.
  SimulationResult Run(int frames, const std::function<void(int, int)>& progress = {});

  // Draws the driving noise from now on as member `sample` of an ensemble of the run
  // seeded `seed` (the constructor's): a stream of its own per sample, sample 0 the
  // constructor's. The camera's draws and everything else stay as they were.
  void SetDrivingNoiseSample(std::uint64_t seed, std::uint64_t sample);
  // Moves the backend's parameters to a draw from their own uncertainty for the rest of
  // the run (OmniBackend::DrawParameters), from a stream of its own per sample of the run
  // seeded `seed`; nothing where the backend's model carries none.
  void DrawModelParameters(std::uint64_t seed, std::uint64_t sample);

  // The whole state: the loop's, the backend's and every robot's behaviour (a copy of
  // each command source, so a go-to-pose source's target and the commands it remembers
  // come back too). Restoring and stepping gives what stepping from the save gave.
  // Restore throws std::invalid_argument for a state of another simulation.
  SimulationState Save() const;
  void Restore(const SimulationState& state);

 private:
  void CheckFinite(int robot, const Pose2& pose, const Twist2& velocity);
  // Robot i's source (null: none) and what it is given in the open frame; throws
  // std::logic_error naming `caller` when no frame is open.
  BehaviourInput SourceInput(int robot, const char* caller, CommandSource** source);
  // The command of robot i's move by force from its true state now (robot frame); ends
  // the move (returns nothing) when the robot has arrived or the time is up.
  std::optional<Twist2> PullCommand(int robot);
  // Driving noise: each present robot whose model simulates it, not being pulled, is
  // moved on by its slip over the frame (robot frame; the backend's velocity untouched,
  // as the wheels and the controller never see it); its spread at the robot's speed and
  // its acceleration since `velocity_before` (per robot, before the frame's step).
  void Slip(const std::vector<Twist2>& velocity_before);

  std::vector<SimRobot> robots_;
  std::unique_ptr<OmniBackend> backend_;
  std::unique_ptr<BallField> ball_;
  SimulationState state_;
  bool frame_open_ = false;  // between BeginFrame and EndFrame
};

}  // namespace twinsim
