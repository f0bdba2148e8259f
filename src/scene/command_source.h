// The command sources a scene can name: scripted sequences, the 45-degree test drive,
// a figure eight, seeded random excitation, a go-to-pose behaviour that sees only
// the delayed observations, and a recorded log played back (kicks included).
//
// Sources are built from a CommandSpec, the parsed and validated `commands:` block of a
// scene (docs/scenes.md); random ones draw their plan from the scene seed when built,
// so a seed fixes the whole run.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "learning/omni_predictor.h"
#include "scene/command_log.h"
#include "sim/behaviour.h"

namespace twinsim {

// The validated `commands:` block of a scene.
struct CommandSpec {
  std::string type = "sequence";  // sequence | test_drive | figure_eight | random | go_to_pose | log
  int line = 0;                   // where the spec begins in its scene file (0: not from a file)

  // sequence
  struct Segment {
    double duration = 0;   // s
    Twist2 command;        // robot frame
    bool ramp = false;     // true: ramp linearly from the previous command to `command`
  };
  std::vector<Segment> segments;
  int repeat = 1;

  // test_drive (seed 000 section 3.4) and figure_eight
  double start = 0.5;          // s of rest before the drive
  double speed = 1.5;          // m/s
  double direction_deg = 45;   // deg, drive direction relative to the heading
  double drive_time = 1.5;     // s, then the command drops to zero (stop hard)
  double size = 1.0;           // m, figure eight half-width
  double period = 8.0;         // s, one figure eight
  int laps = 1;

  // random excitation
  double max_speed = 2.0;         // m/s (also go_to_pose)
  double max_omega = 4.0;         // rad/s (also go_to_pose)
  double min_segment = 0.3;       // s
  double max_segment = 1.5;       // s
  double rest_probability = 0.15;
  double ramp_probability = 0.5;
  double rotate_probability = 0.5;
  double max_centripetal = 0;     // m/s^2; > 0: turn rate capped so |v| |omega| stays below
  double leash = 0;               // m; > 0: beyond this distance from the start (as last
                                  // observed), translation is turned back towards it

  // go_to_pose
  std::vector<Pose2> targets;          // field frame
  double max_accel = 3.0;              // m/s^2, braking profile
  double gain = 4.0;                   // 1/s, position and heading gain
  double position_tolerance = 0.02;    // m
  double angle_tolerance = 0.05;       // rad
  double hold = 0.5;                   // s inside the tolerance before the next target
  // "Predicting away the delay" (seed 000, section 4.1): with a predictor whose horizon
  // is the model's delay D, the behaviour acts on where the robot will be when the
  // command it sends now takes effect, not on the D-frame-old observation.
  // A residual predictor carries its Newtonian model along the observations: that of
  // `predictor_model` (the robot's, set when the scene is read).
  std::string predictor_path;
  std::shared_ptr<const OmniPredictor> predictor;
  std::shared_ptr<const OmniModel> predictor_model;

  // log: a recorded match played back (scene/command_log.h), read when the scene is.
  std::string log_path;    // resolved against the scene file
  std::string log_robot;   // whose rows; default the scene robot's name
  std::shared_ptr<const CommandLog> log;
};

// Every robot of `scene`-like lists driven by the log at `path` instead: robot i's rows
// are those named `names[i]`. Throws InputError as ReadCommandLog.
std::vector<CommandSpec> LogCommandSpecs(const std::string& path, const std::vector<std::string>& names,
                                         double frame_rate);

// Builds the source. `seed` and `robot_index` seed random plans; `duration` (s) is how
// long a random plan must last; `start` is the robot's start pose (open-loop paths).
std::unique_ptr<CommandSource> MakeCommandSource(const CommandSpec& spec, std::uint64_t seed,
                                                 int robot_index, double duration,
                                                 const Pose2& start);

}  // namespace twinsim
