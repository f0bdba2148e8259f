// The robots of a served field as the league's protocol names them: a team (blue or
// yellow) and a robot id, mapped to the robot's index in the simulation. Built from the
// scene's `team:` and `id:` (docs/scenes.md).
#pragma once

#include <string>
#include <vector>

namespace twinsim {

enum class TeamColor { kBlue, kYellow };

// "blue" or "yellow".
const char* TeamName(TeamColor team);
// The other team.
inline TeamColor OtherTeam(TeamColor team) { return team == TeamColor::kBlue ? TeamColor::kYellow : TeamColor::kBlue; }

struct TeamRobot {
  TeamColor team = TeamColor::kBlue;
  int id = 0;  // 0..15
};

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
