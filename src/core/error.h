// The errors twinsim reports to users, and the exit codes they map to (CONTRACT.md):
// InputError -> 2 (bad file, option or schema), CheckFailed -> 1 (the job ran but its
// own check failed, including a simulation that diverged), anything else -> 3.
//
// Which one to throw:
// - InputError for anything a user can get wrong: a file (model, log, scene, predictor,
//   trajectory), a command-line option, an options struct that fails IsValid(), a model
//   that fails Validate(), a task the model cannot do (a point out of reach), data too
//   short or too poor for the job. Give the file and line where they are known
//   (SourceLocation); a library function without them throws the bare message, and a
//   caller that knows the file may catch InputError and throw a new one with the
//   location and context added (never another type).
// - CheckFailed where the job ran and its own check failed: a diverged simulation, a
//   regression beyond tolerance, a candidate effect that fails diagnosis' plausibility
//   checks.
// - std::invalid_argument / std::logic_error only for programming errors that no input
//   can cause: vectors or states of the wrong size passed by our own code, an index out
//   of range, a call in the wrong order. They end as exit 3, "internal error".
// Only src/app/main.cc turns these into exit codes; no other layer converts one type
// into another.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace twinsim {

inline constexpr int kExitOk = 0;
inline constexpr int kExitCheckFailed = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitInternal = 3;

// Where in a file something is: path, 1-based line and column (0 when unknown).
struct SourceLocation {
  std::string path;
  int line = 0;
  int column = 0;
  // "path:line:column: " (parts that are unknown are left out).
  std::string Prefix() const;
};

// Bad user input. what() is one or more lines "PATH:LINE: what is wrong".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  InputError(const SourceLocation& where, const std::string& message)
      : std::runtime_error(where.Prefix() + message) {}
};

// `text` with control characters (but newline and tab) and bytes that are not UTF-8
// written as \xNN, so that a message quoting a binary file is readable on a terminal.
std::string PrintableText(const std::string& text);

// Collects input problems so that a reader can report all of them at once.
class ErrorList {
 public:
  void Add(const SourceLocation& where, const std::string& message) {
    messages_.push_back(where.Prefix() + message);
  }
  void Add(const std::string& message) { messages_.push_back(message); }
  bool empty() const { return messages_.empty(); }
  // Throws one InputError naming every problem, if there are any.
  void ThrowIfAny() const;

 private:
  std::vector<std::string> messages_;
};

// A simulation produced a non-finite or runaway value, or a job's own check failed.
class CheckFailed : public std::runtime_error {
 public:
  explicit CheckFailed(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace twinsim
