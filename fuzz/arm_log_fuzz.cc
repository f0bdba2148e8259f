// Fuzzes the arm log reader (CSV: t,q1..qn,tau1..taun[,qd..,qdd..,qref..]).
#include "fuzz_util.h"
#include "robots/arm/arm_log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return twinsim::fuzz::RunReader([&] { twinsim::ParseArmLog(twinsim::fuzz::AsString(data, size), "log.csv"); });
}
