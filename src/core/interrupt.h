// Stopping a long job cleanly on Ctrl-C (SIGINT) or `kill` (SIGTERM).
//
// The first signal only sets a flag; the job notices it at its next check (a simulation
// frame, a progress update, a batch job boundary) and throws Interrupted, so that
// destructors run and the command's open output transaction (io/output_transaction.h)
// removes everything it had not yet put in place. main() then exits with the shell's
// convention, 128 + the signal number (130 for SIGINT, 143 for SIGTERM). A second signal
// kills the process at once (the default action is restored by the first).
//
//   InstallInterruptHandlers();      // once, in main()
//   for (...) { ThrowIfInterrupted(); ... }
#pragma once

#include <stdexcept>

namespace twinsim {

// The job was asked to stop by a signal. Not an error of the job: nothing is reported
// but the signal's name.
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(int signal_number);
  int signal_number() const { return signal_number_; }
  // 128 + the signal number, the exit status shells give a process killed by it.
  int exit_code() const { return 128 + signal_number_; }

 private:
  int signal_number_;
};

// Catches SIGINT and SIGTERM as described above. Safe to call more than once.
void InstallInterruptHandlers();
// The signal received since start-up (or the last ClearInterrupt()), 0 if none.
int InterruptSignal();
// Throws Interrupted if a signal was received.
void ThrowIfInterrupted();
// Forgets a received signal (tests).
void ClearInterrupt();

}  // namespace twinsim
