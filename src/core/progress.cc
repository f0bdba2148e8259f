#include "core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "core/interrupt.h"

namespace twinsim {

Progress::Progress(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && ::isatty(2)), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { Finish(); }

void Progress::Update(long done, long total, const std::string& detail) {
  ThrowIfInterrupted();  // every long job reports progress: the place to notice Ctrl-C
  if (!enabled_ || total <= 0) return;
  done = std::clamp(done, 0L, total);  // a caller's late step fills the bar, never overruns it
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < 1.0 || (drawn_ && now - last_draw_ < std::chrono::milliseconds(100) && done < total)) return;
  last_draw_ = now;
  drawn_ = true;
  const int width = 30;
  const int filled = static_cast<int>(width * done / total);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(width - filled), '.');
  std::fprintf(stderr, "\r%s [%s] %3ld%% %.1f s %s\033[K", label_.c_str(), bar.c_str(), 100 * done / total, elapsed,
               detail.c_str());
  std::fflush(stderr);
}

void Progress::Status(const std::string& detail) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < 1.0 || (drawn_ && now - last_draw_ < std::chrono::milliseconds(100))) return;
  last_draw_ = now;
  drawn_ = true;
  std::fprintf(stderr, "\r%s %.1f s %s\033[K", label_.c_str(), elapsed, detail.c_str());
  std::fflush(stderr);
}

void Progress::Finish() {
  if (drawn_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    drawn_ = false;
  }
}

}  // namespace twinsim
