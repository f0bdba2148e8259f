// What every robot sent, frame by frame, as a file that plays back exactly: the
// commands.csv `twinsim serve` writes (what the teams' software sent over the network
// and what the scripted robots sent), which `twinsim run --commands FILE` and a scene's
// `commands: {type: log, file: ...}` replay (docs/scenes.md, docs/serve.md).
//
//   frame,t,robot,vx_cmd,vy_cmd,omega_cmd,kick_speed,kick_angle,dribbler_speed
//   0,0.000000000,b0,0,0,0,0,0,0
//
// One row per robot per frame, in frame order; velocities in the robot's frame (m/s,
// rad/s; a global velocity already turned as the field turned it), kick_speed m/s,
// kick_angle rad, dribbler_speed rpm. The command columns are written with 17
// significant digits, so they read back to the same doubles and a replay takes the
// same path, bit for bit.
//
// The reader takes that file and any CSV with t (or frame), vx_cmd, vy_cmd and
// omega_cmd columns, such as the contract's log (trajectory.csv) and truth.csv.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/pose.h"
#include "sim/ball_command.h"
#include "sim/behaviour.h"
#include "sim/omni_simulation.h"

namespace twinsim {

// One robot's commands, keyed by frame.
struct CommandLog {
  std::string path;                 // where it was read from (for messages)
  std::vector<int> frames;          // strictly increasing
  std::vector<Twist2> moves;        // robot frame, per row
  std::vector<BallCommand> balls;   // per row; zero where the file has no such column
};

// commands.csv for a finished run (every robot, every frame).
std::string CommandsCsv(const SimulationResult& result);
// Its header, and one robot's row of frame `frame` appended to *out (nothing for a
// robot off the field), for a file written as the run goes.
inline constexpr const char* kCommandsHeader =
    "frame,t,robot,vx_cmd,vy_cmd,omega_cmd,kick_speed,kick_angle,dribbler_speed\n";
void AppendCommandRow(long long frame, const std::string& robot, const FrameRecord& record, std::string* out);

// Reads robot `robot`'s rows of the file at `path` (all rows when the file has no
// `robot` column). A row's frame is its `frame` column, else round(t * frame_rate).
// Throws InputError "path:line:column: ..." for a missing file or column, a value that
// is not a number or out of range (speeds beyond 20 m/s or 100 rad/s, kick_speed beyond
// 0..20 m/s, kick_angle beyond 0..89 degrees, dribbler_speed beyond 0..1e5 rpm), frames
// that do not increase, and a file without a row for the robot (naming the robots it
// has).
CommandLog ReadCommandLog(const std::string& path, const std::string& robot, double frame_rate);

// Plays a log back: in frame k the move of the last row at or before k (zero before the
// first row; the last row's move holds after the file ends, as a served robot keeps its
// last command); the dribbler holds the same way; a kick acts only in its own row's
// frame.
class LogCommandSource : public CommandSource {
 public:
  explicit LogCommandSource(std::shared_ptr<const CommandLog> log);
  Twist2 Command(const BehaviourInput& in) override;
  BallCommand Ball(const BehaviourInput& in) override;
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<LogCommandSource>(*this); }

 private:
  // The row in force at `frame`, or -1 before the first.
  int RowAt(int frame) const;

  std::shared_ptr<const CommandLog> log_;
};

}  // namespace twinsim
