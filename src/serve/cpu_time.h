// What the machine did with the serving thread's CPU besides running it, from the
// kernel's per-CPU accounting (/proc/stat, in clock ticks of 1/sysconf(_SC_CLK_TCK) s,
// 10 ms here): the time stolen by the hypervisor (another guest ran on the real CPU: a
// virtual machine's thread cannot run however high its priority) and the time spent in
// hard and soft interrupts. serve's timing (serve/live_field.h ServeTiming::Stall) reads
// it at each frame's start and end, so a late frame says whether it was stolen.
//
//   CpuTime cpu;
//   CpuTicks before = cpu.Now();   // of the CPU the calling thread runs on
//   ...
//   CpuTicks after = cpu.Now();
//   if (after.cpu >= 0 && after.cpu == before.cpu) stolen = cpu.Seconds(after.steal - before.steal);
#pragma once

#include <string_view>
#include <vector>

namespace twinsim {

struct CpuTicks {
  int cpu = -1;              // the CPU read; -1: nothing could be read
  long long steal = 0;       // ticks stolen by the hypervisor
  long long interrupts = 0;  // ticks in hard and soft interrupts
};

class CpuTime {
 public:
  CpuTime();
  ~CpuTime();
  CpuTime(const CpuTime&) = delete;
  CpuTime& operator=(const CpuTime&) = delete;

  bool ok() const { return fd_ >= 0; }
  // The counters of the CPU the calling thread runs on: one read of /proc/stat (7 us on
  // this 2-CPU machine; the kernel writes every CPU's line each time).
  CpuTicks Now() const;
  double Seconds(long long ticks) const { return static_cast<double>(ticks) / ticks_per_second_; }

  // The counters of CPU `cpu`'s line of a /proc/stat text; cpu -1 when the line is absent
  // or not whole.
  static CpuTicks Parse(std::string_view text, int cpu);

 private:
  int fd_ = -1;
  double ticks_per_second_ = 100;
  mutable std::vector<char> buffer_;  // one thread reads: serve's
};

}  // namespace twinsim
