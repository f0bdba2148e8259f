// What every ODE engine of the project needs from ODE's process-wide state, in one
// place: ODE initialised once per process, its per-thread data allocated once per
// thread, and worlds that can step on several threads at once.
//
//   OdeWorld world;                // dWorldCreate() with its own step scheduler
//   dWorldSetGravity(world.id(), 0, 0, -9.81);
//   ... EnsureOdeInitialized() at the top of every function that steps or builds ...
#pragma once

#include <ode/ode.h>

namespace twinsim {

// dInitODE2 once per process (dCloseODE is never called: engines may outlive main()),
// and dAllocateODEDataForThread once per calling thread.
void EnsureOdeInitialized();

// A field's world: gravity (gx, gy, gz) m/s^2 and bodies that never fall asleep (robots
// and balls often stand still between commands; a sleeping body would ignore the next).
inline void SetUpFieldWorld(dWorldID world, double gx, double gy, double gz) {
  dWorldSetGravity(world, gx, gy, gz);
  dWorldSetAutoDisableFlag(world, 0);
}

// A contact surface with Coulomb friction mu (ODE's Approx1: the limit is mu times the
// normal force), restitution `bounce` above `bounce_vel` m/s of approach, and a soft
// constraint of `erp` and `cfm`.
inline dSurfaceParameters BouncingSurface(double mu, double bounce, double bounce_vel, double erp, double cfm) {
  dSurfaceParameters s{};
  s.mode = dContactApprox1 | dContactBounce | dContactSoftERP | dContactSoftCFM;
  s.mu = mu;
  s.bounce = bounce;
  s.bounce_vel = bounce_vel;
  s.soft_erp = erp;
  s.soft_cfm = cfm;
  return s;
}

// A dWorldID that owns its own single-threaded step scheduler: ODE's default scheduler
// is one process-wide object, and two worlds stepping on two threads trip over it.
// Destroying it destroys the world with every body and joint in it.
class OdeWorld {
 public:
  OdeWorld();
  ~OdeWorld();
  OdeWorld(const OdeWorld&) = delete;
  OdeWorld& operator=(const OdeWorld&) = delete;

  dWorldID id() const { return world_; }

 private:
  dWorldID world_ = nullptr;
  dThreadingImplementationID threading_ = nullptr;
};

}  // namespace twinsim
