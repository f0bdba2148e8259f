#include "engines/omni_engine.h"

#include <cstdio>

#include "core/error.h"
#include "engines/analytic/analytic_omni_engine.h"
#ifdef TWINSIM_HAVE_ODE
#include "engines/ode/ode_omni_engine.h"
#endif
#ifdef TWINSIM_HAVE_BULLET
#include "engines/bullet/bullet_omni_engine.h"
#endif

namespace twinsim {

std::string DescribeGrip(const GripCheck& grip) {
  if (grip.beyond == 0 || grip.steps == 0) return "";
  // A few steps a hair over the grip (in a replay of a minute with its predictions 16
  // frames ahead, 5 of half a million steps at up to 1.0025 times it) slide the robot by
  // nothing a camera sees: not said.
  const double share = static_cast<double>(grip.beyond) / static_cast<double>(grip.steps);
  if (grip.worst < kGripWorthSaying && share < kGripShareWorthSaying) return "";
  char text[640];
  std::snprintf(text, sizeof text,
                "the analytic model's wheels needed more grip than they have (wheel_friction times their load) on "
                "%.2g %% of the steps simulated, up to %.2g times it: a robot of the model's grip slips there and the "
                "analytic model cannot. Where a logged robot made those motions, its grip is larger than the model "
                "says (wheels.friction, or mass and inertia from a data sheet), and ode or bullet, which slip there, "
                "follow it less well; where it slipped, they simulate the slip (docs/backends.md)",
                100.0 * share, grip.worst);
  return text;
}

std::vector<std::string> AvailableOmniEngines() {
  std::vector<std::string> names = {"analytic"};
#ifdef TWINSIM_HAVE_ODE
  names.push_back("ode");
#endif
#ifdef TWINSIM_HAVE_BULLET
  names.push_back("bullet");
#endif
  return names;
}

std::unique_ptr<OmniEngine> MakeOmniEngine(const std::string& name,
                                           const std::vector<OmniModel>& robots,
                                           const FieldModel& field) {
  if (name == "analytic") return MakeAnalyticOmniEngine(robots, field);
  if (name == "ode") {
#ifdef TWINSIM_HAVE_ODE
    return MakeOdeOmniEngine(robots, field);
#else
    throw InputError("ode backend not compiled; rebuild with -DTWINSIM_WITH_ODE=ON");
#endif
  }
  if (name == "bullet") {
#ifdef TWINSIM_HAVE_BULLET
    return MakeBulletOmniEngine(robots, field);
#else
    throw InputError("bullet backend not compiled; rebuild with -DTWINSIM_WITH_BULLET=ON");
#endif
  }
  throw InputError("unknown physics backend '" + name + "' (known: analytic, ode, bullet, learned)");
}

}  // namespace twinsim
