#include "serve/team_roster.h"

#include <cmath>
#include <stdexcept>

#include "core/math_constants.h"
#include "robots/omni/omni_kinematics.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

const char* TeamName(TeamColor team) { return team == TeamColor::kBlue ? "blue" : "yellow"; }

TeamRoster::TeamRoster(std::vector<TeamRobot> robots) : robots_(std::move(robots)) {
  for (std::size_t i = 0; i < robots_.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (robots_[i].team == robots_[j].team && robots_[i].id == robots_[j].id)
        throw std::invalid_argument("TeamRoster: " + std::string(TeamName(robots_[i].team)) + " robot " +
                                    std::to_string(robots_[i].id) + " appears twice");
}

std::optional<ProtocolWheelMap> WheelMapFor(const OmniModel& model) {
  if (model.num_wheels() != 4) return std::nullopt;
  // The protocol's order, by quadrant: front right (-90, 0), back right (-180, -90),
  // back left (90, 180), front left (0, 90) degrees.
  constexpr double kLow[4] = {-kPi / 2, -kPi, kPi / 2, 0};
  int wheel_of[4] = {-1, -1, -1, -1};
  for (int i = 0; i < 4; ++i) {
    const double a = std::remainder(model.wheel_angles[static_cast<std::size_t>(i)], 2 * kPi);  // [-pi, pi]; on a boundary: no quadrant
    for (int q = 0; q < 4; ++q) {
      if (a > kLow[q] && a < kLow[q] + kPi / 2) {
        if (wheel_of[q] >= 0) return std::nullopt;
        wheel_of[q] = i;
      }
    }
  }
  for (int w : wheel_of)
    if (w < 0) return std::nullopt;
  const OmniKinematics kinematics(model);
  ProtocolWheelMap map;  // body_from_wheels is per rad/s of wheel spin
  for (int q = 0; q < 4; ++q) map.col(q) = kinematics.body_from_wheels().col(wheel_of[q]) / model.wheel_radius;
  return map;
}

int TeamRoster::Find(TeamColor team, long long id) const {
  for (std::size_t i = 0; i < robots_.size(); ++i)
    if (robots_[i].team == team && robots_[i].id == id) return static_cast<int>(i);
  return -1;
}

}  // namespace twinsim
