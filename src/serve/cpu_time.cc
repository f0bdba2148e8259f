#include "serve/cpu_time.h"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <sstream>

namespace twinsim {

CpuTime::CpuTime(int cpu) : label_(cpu < 0 ? "cpu" : "cpu" + std::to_string(cpu)) {
  fd_ = open("/proc/stat", O_RDONLY | O_CLOEXEC);
  const long hz = sysconf(_SC_CLK_TCK);
  if (hz > 0) ticks_per_second_ = static_cast<double>(hz);
}

CpuTime::~CpuTime() {
  if (fd_ >= 0) close(fd_);
}

CpuTicks CpuTime::Now() const {
  if (fd_ < 0) return {};
  // The per-CPU lines come first; the interrupt counts after them can be long.
  std::array<char, 8192> buffer{};
  const ssize_t n = pread(fd_, buffer.data(), buffer.size() - 1, 0);
  if (n <= 0) return {};
  return Parse(std::string(buffer.data(), static_cast<std::size_t>(n)), label_);
}

CpuTicks CpuTime::Parse(const std::string& text, const std::string& label) {
  // "cpuN user nice system idle iowait irq softirq steal guest guest_nice" (proc(5)).
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::string name;
    fields >> name;
    if (name != label) continue;
    std::array<long long, 8> v{};
    for (long long& x : v) fields >> x;
    if (!fields) return {};
    return CpuTicks{v[7], v[5] + v[6]};
  }
  return {};
}

}  // namespace twinsim
