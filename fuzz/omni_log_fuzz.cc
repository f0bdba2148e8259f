// Fuzzes the omni log reader (CSV: t,x,y,theta,vx_cmd,vy_cmd,omega_cmd).
#include "fuzz_util.h"
#include "robots/omni/omni_log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader([&] { twinsim::ParseOmniLog(twinsim::fuzz::AsString(data, size), "log.csv"); });
}
