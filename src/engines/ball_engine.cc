#include "engines/ball_engine.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/math_constants.h"
#ifdef TWINSIM_HAVE_ODE
#include "engines/ode/ode_ball_engine.h"
#endif
#ifdef TWINSIM_HAVE_BULLET
#include "engines/bullet/bullet_ball_engine.h"
#endif

namespace twinsim {

std::vector<Eigen::Vector2d> ChassisOutline(const OmniModel& model, int arc_segments) {
  const double r = model.chassis_radius, front = model.FrontDistance();
  // The arc runs from the front's left corner, round the back, to its right corner.
  const double corner = std::acos(std::min(front / r, 1.0));  // rad; a front beyond the radius: none
  std::vector<Eigen::Vector2d> outline;
  for (int k = 0; k <= arc_segments; ++k) {
    const double a = corner + (2 * kPi - 2 * corner) * k / arc_segments;
    outline.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return outline;  // the last point back to the first is the flat front
}

std::vector<std::string> AvailableBallEngines() {
  // Every omni engine built but the analytic one, which has no ball.
  std::vector<std::string> names;
  for (const std::string& n : AvailableOmniEngines())
    if (n != "analytic") names.push_back(n);
  return names;
}

std::unique_ptr<BallEngine> MakeBallEngine(const std::string& name, const BallModel& ball,
                                           const std::vector<OmniModel>& robots, const FieldModel& field) {
  if (name == "ode") {
#ifdef TWINSIM_HAVE_ODE
    return MakeOdeBallEngine(ball, robots, field);
#else
    throw InputError("ode backend not compiled; rebuild with -DTWINSIM_WITH_ODE=ON");
#endif
  }
  if (name == "bullet") {
#ifdef TWINSIM_HAVE_BULLET
    return MakeBulletBallEngine(ball, robots, field);
#else
    throw InputError("bullet backend not compiled; rebuild with -DTWINSIM_WITH_BULLET=ON");
#endif
  }
  throw InputError("unknown ball engine '" + name + "' (known: ode, bullet)");
}

}  // namespace twinsim
