// Fuzzes the reader of a batch job's result.json, which `batch --resume` trusts to skip a
// finished job: a damaged file must mean "run the job again", never a crash.
#include "batch/batch_summary.h"
#include "batch/sweep.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const twinsim::SweepJob job = [] {
    twinsim::SweepJob j;
    // As in the seed tests/fuzz/corpus/job_result/run_ok.json, so that inputs near it get
    // past the identity check into the metrics.
    j.index = 0;
    j.id = "0000";
    j.seed = 897828584;
    return j;
  }();
  return twinsim::fuzz::RunReader([&] { twinsim::ParseJobResultJson(twinsim::fuzz::AsString(data, size), job); });
}
