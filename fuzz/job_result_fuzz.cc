// Fuzzes the reader of a batch job's result.json, which `batch --resume` trusts to skip a
// finished job: a damaged file must mean "run the job again", never a crash.
#include "batch/batch_summary.h"
#include "batch/sweep.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const twinsim::SweepJob job = [] {
    twinsim::SweepJob j;
    j.index = 0;
    j.id = "000000";
    return j;
  }();
  return twinsim::fuzz::RunReader([&] { twinsim::ParseJobResultJson(twinsim::fuzz::AsString(data, size), job); });
}
