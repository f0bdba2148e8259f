// All or nothing: the files one command writes appear together or not at all.
//
// While a transaction is open on a thread, WriteFileAtomically() (io/atomic_file.h), and
// with it every writer of the project, writes each file complete under a temporary name
// beside its target (NAME.tmpPID) and defers the rename. Commit() renames them all into
// place; a transaction destroyed without Commit() (an error, an interrupt) removes the
// temporaries and the folders it created that are left empty, so a failed command leaves
// no file under a final name. main() opens one around every command.
//
//   OutputTransaction outputs;
//   RunTheCommand();      // writes trajectory.csv, path.png, ...
//   outputs.Commit();     // now they all exist
//
// For tests of this promise, the environment variable TWINSIM_FAIL_WRITE=NAME makes the
// write of any file called NAME fail with InputError, as a full disk would.
#pragma once

#include <string>
#include <vector>

namespace twinsim {

class OutputTransaction {
 public:
  // Opens a transaction on this thread. Throws std::logic_error if one is open already.
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  // Moves every file written into place, in the order written. Throws InputError (the
  // rest left in place, temporaries removed) when a target cannot be replaced, e.g. it is
  // a folder; checked for all targets before the first rename.
  void Commit();
  // The transaction open on this thread, or nullptr.
  static OutputTransaction* Current();

  // Called by WriteFileAtomically: `temp` holds the complete content for `target`.
  void Defer(const std::string& temp, const std::string& target);
  // Called by WriteFileAtomically before it creates `folder`, so that an abort can
  // remove what it created.
  void NoteFolderCreated(const std::string& folder);

 private:
  void Abort();

  struct Pending {
    std::string temp, target;
  };
  std::vector<Pending> pending_;
  std::vector<std::string> created_folders_;  // outermost first
  OutputTransaction* previous_ = nullptr;
  bool done_ = false;
};

// Within its scope, writes on this thread go straight to their final names again (batch
// job folders, each complete when its result.json is written last, so that a resumed
// sweep keeps the jobs that finished).
class OutputTransactionPause {
 public:
  OutputTransactionPause();
  ~OutputTransactionPause();
  OutputTransactionPause(const OutputTransactionPause&) = delete;
  OutputTransactionPause& operator=(const OutputTransactionPause&) = delete;

 private:
  OutputTransaction* paused_;
};

// Throws InputError if TWINSIM_FAIL_WRITE names this file (see above).
void MaybeFailWriteForTest(const std::string& path);

}  // namespace twinsim
