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
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/delay_line.h"
#include "core/rng.h"
#include "sim/behaviour.h"
#include "sim/omni_backend.h"

namespace twinsim {

struct SimRobot {
  std::string name;
  OmniModel model;
  Pose2 start;
  std::unique_ptr<CommandSource> commands;
};

// One row of what happened to one robot in one frame.
struct FrameRecord {
  double t = 0;            // s
  bool observed = false;   // false: this frame's observation was lost (not logged)
  Pose2 seen;              // what the observer received at t (captured D_v frames earlier)
  double stamp = 0;        // s, the time the observer logs for the frame: t off by the camera's jitter
  Twist2 command;          // sent at t, robot frame
  Pose2 truth;             // the true pose at t
  Twist2 truth_velocity;   // robot frame, true
};

struct SimulationResult {
  std::string backend;
  FrameTiming timing;
  std::vector<std::string> robot_names;
  std::vector<std::vector<FrameRecord>> frames;  // [robot][frame]
};

struct SimulationState {
  int frame = 0;
  Rng rng;
  std::vector<DelayLine<Twist2>> commands_in_flight;                // per robot
  std::vector<DelayLine<std::optional<Pose2>>> captures_in_flight;  // per robot
  std::vector<std::optional<Pose2>> last_captured;                  // per robot, what the camera repeats
  std::vector<std::vector<Observation>> delivered;                  // per robot, recent window
  // Per robot, the true state of the last frame that passed the divergence check
  // (t, truth, truth_velocity only): what a divergence message reports as last good.
  std::vector<FrameRecord> last_good;
  OmniBackendState backend;
  // Per robot, a copy of its behaviour as it was (null: none); filled by Save() only.
  std::vector<std::shared_ptr<const CommandSource>> behaviours;
};

class Simulation {
 public:
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
  // What robot i's own CommandSource sends in the open frame (zero without one), for a
  // loop that drives some robots from outside and the others by their sources. Throws
  // std::logic_error when no frame is open.
  Twist2 SourceCommand(int robot);
  // The observations delivered to robot i so far (the newest kObservationWindow, oldest
  // first).
  const std::vector<Observation>& delivered(int robot) const {
    return state_.delivered.at(static_cast<std::size_t>(robot));
  }
  // Puts robot i at `pose` moving at `velocity` (robot frame) now, as a referee's hand
  // would: the commands and captures already in flight stay in flight.
  void Teleport(int robot, const Pose2& pose, const Twist2& velocity);
  const std::string& robot_name(int robot) const { return robots_.at(static_cast<std::size_t>(robot)).name; }
  const OmniModel& robot_model(int robot) const { return robots_.at(static_cast<std::size_t>(robot)).model; }

  // Runs `frames` frames; `progress(done, total)` is called now and then.
  SimulationResult Run(int frames, const std::function<void(int, int)>& progress = {});

  // The whole state: the loop's, the backend's and every robot's behaviour (a copy of
  // each command source, so a go-to-pose source's target and the commands it remembers
  // come back too). Restoring and stepping gives what stepping from the save gave.
  // Restore throws std::invalid_argument for a state of another simulation.
  SimulationState Save() const;
  void Restore(const SimulationState& state);

 private:
  void CheckFinite(int robot, const Pose2& pose, const Twist2& velocity);

  std::vector<SimRobot> robots_;
  std::unique_ptr<OmniBackend> backend_;
  SimulationState state_;
  bool frame_open_ = false;  // between BeginFrame and EndFrame
};

}  // namespace twinsim
