#include "serve/team_roster.h"

#include <stdexcept>

namespace twinsim {

const char* TeamName(TeamColor team) { return team == TeamColor::kBlue ? "blue" : "yellow"; }

TeamRoster::TeamRoster(std::vector<TeamRobot> robots) : robots_(std::move(robots)) {
  for (std::size_t i = 0; i < robots_.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (robots_[i].team == robots_[j].team && robots_[i].id == robots_[j].id)
        throw std::invalid_argument("TeamRoster: " + std::string(TeamName(robots_[i].team)) + " robot " +
                                    std::to_string(robots_[i].id) + " appears twice");
}

int TeamRoster::Find(TeamColor team, long long id) const {
  for (std::size_t i = 0; i < robots_.size(); ++i)
    if (robots_[i].team == team && robots_[i].id == id) return static_cast<int>(i);
  return -1;
}

}  // namespace twinsim
