// What the machine did with a CPU besides running the serving thread, from the kernel's
// per-CPU accounting (/proc/stat, in clock ticks of 1/sysconf(_SC_CLK_TCK) s, 10 ms here):
// the time stolen by the hypervisor (another guest ran on the real CPU: a virtual
// machine's thread cannot run however high its priority) and the time spent in hard and
// soft interrupts. serve's timing (serve/live_field.h ServeTiming::Stall) reads it at each
// frame's start and end, so a late frame says whether it was stolen.
//
//   CpuTime cpu(1);                 // CPU 1 (-1: all CPUs together)
//   CpuTicks before = cpu.Now();
//   ...
//   double stolen = cpu.Seconds(cpu.Now().steal - before.steal);
#pragma once

#include <string>

namespace twinsim {

struct CpuTicks {
  long long steal = 0;       // ticks stolen by the hypervisor
  long long interrupts = 0;  // ticks in hard and soft interrupts
};

class CpuTime {
 public:
  // Reads CPU `cpu`'s line, or the line of all CPUs for -1. Without /proc/stat (or the
  // line) every reading is zero: ok() says whether it is real.
  explicit CpuTime(int cpu);
  ~CpuTime();
  CpuTime(const CpuTime&) = delete;
  CpuTime& operator=(const CpuTime&) = delete;

  bool ok() const { return fd_ >= 0; }
  CpuTicks Now() const;  // one read of /proc/stat, about 7 us
  double Seconds(long long ticks) const { return static_cast<double>(ticks) / ticks_per_second_; }

  // The counters of the line `label` ("cpu", "cpu1") of a /proc/stat text; zero when absent.
  static CpuTicks Parse(const std::string& text, const std::string& label);

 private:
  int fd_ = -1;
  std::string label_;
  double ticks_per_second_ = 100;
};

}  // namespace twinsim
