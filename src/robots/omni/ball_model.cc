#include "robots/omni/ball_model.h"

#include <cmath>
#include <sstream>

namespace twinsim {

bool BallModel::IsValid(std::string* why) const {
  std::ostringstream out;
  auto check = [&out](const char* name, double v, double lo, double hi, bool open_lo) {
    if (!std::isfinite(v) || v > hi || (open_lo ? v <= lo : v < lo))
      out << name << " " << v << " is not in " << (open_lo ? "(" : "[") << lo << ", " << hi << "]\n";
  };
  check("radius", radius, 0.005, 0.2, false);
  check("mass", mass, 0.001, 10, false);
  check("sliding_friction", sliding_friction, 0, 2, false);
  check("rolling_friction", rolling_friction, 0, 1, false);
  check("restitution", restitution, 0, 1, false);
  check("floor_restitution", floor_restitution, 0, 1, false);
  check("robot_friction", robot_friction, 0, 2, false);
  check("drag", drag, 0, 5, false);
  *why = out.str();
  return why->empty();
}

void ReadBallModel(YamlMap& m, BallModel* ball) {
  m.Get("radius", &ball->radius, InRange(0.005, 0.2));
  m.Get("mass", &ball->mass, InRange(0.001, 10));
  m.Get("sliding_friction", &ball->sliding_friction, InRange(0, 2));
  m.Get("rolling_friction", &ball->rolling_friction, InRange(0, 1));
  m.Get("restitution", &ball->restitution, InRange(0, 1));
  m.Get("floor_restitution", &ball->floor_restitution, InRange(0, 1));
  m.Get("robot_friction", &ball->robot_friction, InRange(0, 2));
  m.Get("drag", &ball->drag, InRange(0, 5));
}

}  // namespace twinsim
