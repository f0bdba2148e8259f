// The robots of a served field as the league's protocol names them: a team (blue or
// yellow) and a robot id, mapped to the robot's index in the simulation. Built from the
// scene's `team:` and `id:` (docs/scenes.md).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace twinsim {

enum class TeamColor { kBlue, kYellow };

// "blue" or "yellow".
const char* TeamName(TeamColor team);
// The other team.
inline TeamColor OtherTeam(TeamColor team) { return team == TeamColor::kBlue ? TeamColor::kYellow : TeamColor::kBlue; }

// The protocol's wheel velocities (MoveWheelVelocity: front right, back right, back
// left, front left; m/s at the rim, positive where the wheel drives the robot
// counter-clockwise about its centre, docs/serve.md) to the robot's body velocity
// (robot frame; m/s, m/s, rad/s).
using ProtocolWheelMap = Eigen::Matrix<double, 3, 4>;

struct TeamRobot {
  TeamColor team = TeamColor::kBlue;
  int id = 0;  // 0..15
  // Empty: the robot's wheels are not the protocol's four (see WheelMapFor).
  std::optional<ProtocolWheelMap> wheels{};
};

struct OmniModel;
// The map for a robot with four wheels, one in each quadrant around its centre (front
// right: -90 to 0 deg from its heading, back right, back left, front left); empty for
// any other layout (three wheels, two in one quadrant, one on a quadrant's edge).
std::optional<ProtocolWheelMap> WheelMapFor(const OmniModel& model);

class TeamRoster {
 public:
  // robots[i] is simulation robot i. Throws std::invalid_argument for a (team, id) that
  // appears twice (scenes are checked when loaded).
  explicit TeamRoster(std::vector<TeamRobot> robots);
  int size() const { return static_cast<int>(robots_.size()); }
  const TeamRobot& robot(int index) const { return robots_.at(static_cast<std::size_t>(index)); }
  // The index of `team`'s robot `id`, -1 when the team has no such robot.
  int Find(TeamColor team, long long id) const;

 private:
  std::vector<TeamRobot> robots_;
};

}  // namespace twinsim
