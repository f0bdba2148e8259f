// A deterministic parallel loop: ParallelFor(n, threads, fn) calls fn(i) once for every
// i in [0, n) on up to `threads` worker threads (0: one per core). Each call must write
// only its own result slot (e.g. results[i]); the order in which calls run is not
// fixed, so results do not depend on the thread count as long as fn(i) depends on i
// alone. The first exception thrown by any call is rethrown on the caller's thread
// after every worker has stopped.
#pragma once

#include <functional>

namespace twinsim {

// The number of worker threads `requested` stands for (0: hardware concurrency, >= 1).
int ResolveThreadCount(int requested);

void ParallelFor(int n, int threads, const std::function<void(int)>& fn);

}  // namespace twinsim
