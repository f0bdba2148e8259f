#include "serve/cpu_time.h"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <array>
#include <charconv>
#include <cstdio>

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
  return Parse(std::string_view(buffer_.data(), static_cast<std::size_t>(n)), cpu);
}

CpuTicks CpuTime::Parse(std::string_view text, int cpu) {
  // "cpuN user nice system idle iowait irq softirq steal guest guest_nice" (proc(5)),
  // read in place: the serving loop reads it each frame, so nothing is allocated.
  char label[24];
  const int length = std::snprintf(label, sizeof label, "cpu%d ", cpu);
  std::size_t at = 0;
  while (at < text.size() && text.compare(at, static_cast<std::size_t>(length), label) != 0) {
    at = text.find('\n', at);
    if (at == std::string_view::npos) return {};
    ++at;
  }
  const std::size_t end = text.find('\n', at);
  if (at >= text.size() || end == std::string_view::npos) return {};  // absent, or cut short by the read
  const char* p = text.data() + at + length;
  const char* const stop = text.data() + end;
  std::array<long long, 8> v{};
  for (long long& x : v) {
    while (p < stop && *p == ' ') ++p;
    const std::from_chars_result r = std::from_chars(p, stop, x);
    if (r.ec != std::errc()) return {};
    p = r.ptr;
  }
  return CpuTicks{cpu, v[7], v[5] + v[6]};
}

}  // namespace twinsim
