#include "engines/ode/ode_world.h"

#include <mutex>

namespace twinsim {

void EnsureOdeInitialized() {
  static std::once_flag once;
  std::call_once(once, [] { dInitODE2(0); });
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}

OdeWorld::OdeWorld() {
  EnsureOdeInitialized();
  world_ = dWorldCreate();
  threading_ = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(world_, dThreadingImplementationGetFunctions(threading_), threading_);
}

OdeWorld::~OdeWorld() {
  dWorldSetStepThreadingImplementation(world_, nullptr, nullptr);
  dWorldDestroy(world_);
  dThreadingFreeImplementation(threading_);
}

}  // namespace twinsim
