#include "serve/cpu_time.h"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <array>
#include <sstream>

namespace twinsim {
namespace {

// Enough for the per-CPU lines of 1000 CPUs, which come first.
constexpr std::size_t kReadBytes = 1 << 17;

}  // namespace

CpuTime::CpuTime() : buffer_(kReadBytes) {
  fd_ = open("/proc/stat", O_RDONLY | O_CLOEXEC);
  const long hz = sysconf(_SC_CLK_TCK);
  if (hz > 0) ticks_per_second_ = static_cast<double>(hz);
}

CpuTime::~CpuTime() {
  if (fd_ >= 0) close(fd_);
}

CpuTicks CpuTime::Now() const {
  const int cpu = sched_getcpu();
  if (fd_ < 0 || cpu < 0) return {};
  const ssize_t n = pread(fd_, buffer_.data(), buffer_.size(), 0);
  if (n <= 0) return {};
  return Parse(std::string(buffer_.data(), static_cast<std::size_t>(n)), cpu);
}

CpuTicks CpuTime::Parse(const std::string& text, int cpu) {
  // "cpuN user nice system idle iowait irq softirq steal guest guest_nice" (proc(5)).
  const std::string label = "cpu" + std::to_string(cpu) + " ";
  std::size_t at = text.rfind("\n" + label);
  at = at == std::string::npos ? (text.compare(0, label.size(), label) == 0 ? 0 : at) : at + 1;
  if (at == std::string::npos) return {};
  const std::size_t end = text.find('\n', at);
  if (end == std::string::npos) return {};  // cut short by the read
  std::istringstream fields(text.substr(at + label.size(), end - at - label.size()));
  std::array<long long, 8> v{};
  for (long long& x : v) fields >> x;
  if (!fields) return {};
  return CpuTicks{cpu, v[7], v[5] + v[6]};
}

}  // namespace twinsim
