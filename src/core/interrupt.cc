#include "core/interrupt.h"

#include <atomic>
#include <csignal>
#include <string>

namespace twinsim {
namespace {

// Written by the handler, read by every thread: a lock-free atomic is safe for both.
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void OnSignal(int signal_number) {
  g_signal.store(signal_number, std::memory_order_relaxed);
  // The next signal takes the default action: a job that does not reach a check soon
  // can still be stopped at once.
  std::signal(signal_number, SIG_DFL);
}

std::string SignalName(int signal_number) {
  if (signal_number == SIGINT) return "SIGINT";
  if (signal_number == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal_number);
}

}  // namespace

Interrupted::Interrupted(int signal_number)
    : std::runtime_error("interrupted by " + SignalName(signal_number) + "; no output was put in place"),
      signal_number_(signal_number) {}

void InstallInterruptHandlers() {
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
}

int InterruptSignal() { return g_signal.load(std::memory_order_relaxed); }

void ThrowIfInterrupted() {
  if (const int s = InterruptSignal(); s != 0) throw Interrupted(s);
}

void ClearInterrupt() { g_signal.store(0, std::memory_order_relaxed); }

}  // namespace twinsim
