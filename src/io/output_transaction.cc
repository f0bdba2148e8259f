#include "io/output_transaction.h"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "core/error.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

thread_local OutputTransaction* t_current = nullptr;

}  // namespace

OutputTransaction::OutputTransaction() {
  if (t_current != nullptr) throw std::logic_error("OutputTransaction: one is open on this thread already");
  t_current = this;
}

OutputTransaction::~OutputTransaction() {
  if (!done_) Abort();
  if (t_current == this) t_current = nullptr;
}

OutputTransaction* OutputTransaction::Current() { return t_current; }

void OutputTransaction::Defer(const std::string& temp, const std::string& target) {
  for (Pending& p : pending_) {
    if (p.target == target) {  // written again: the newer content wins
      if (p.temp != temp) {
        std::error_code ec;
        fs::remove(p.temp, ec);
        p.temp = temp;
      }
      return;
    }
  }
  pending_.push_back({temp, target});
}

void OutputTransaction::NoteFolderCreated(const std::string& folder) { created_folders_.push_back(folder); }

void OutputTransaction::Commit() {
  if (done_) throw std::logic_error("OutputTransaction: committed twice");
  std::error_code ec;
  for (const Pending& p : pending_) {
    if (fs::is_directory(p.target, ec)) {
      Abort();
      throw InputError(SourceLocation{p.target}, "cannot write the file: a folder of that name is in the way");
    }
  }
  done_ = true;
  if (t_current == this) t_current = nullptr;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    fs::rename(pending_[i].temp, pending_[i].target, ec);
    if (ec) {
      const std::string reason = ec.message();
      for (std::size_t j = i; j < pending_.size(); ++j) fs::remove(pending_[j].temp, ec);
      throw InputError(SourceLocation{pending_[i].target}, "cannot rename into place: " + reason);
    }
  }
}

void OutputTransaction::Abort() {
  done_ = true;
  std::error_code ec;
  for (const Pending& p : pending_) fs::remove(p.temp, ec);
  // Innermost first; fs::remove leaves a folder that is not empty.
  for (auto it = created_folders_.rbegin(); it != created_folders_.rend(); ++it) fs::remove(*it, ec);
  pending_.clear();
}

OutputTransactionPause::OutputTransactionPause() : paused_(t_current) { t_current = nullptr; }
OutputTransactionPause::~OutputTransactionPause() { t_current = paused_; }

void MaybeFailWriteForTest(const std::string& path) {
  static const char* const name = std::getenv("TWINSIM_FAIL_WRITE");
  if (name != nullptr && *name != '\0' && fs::path(path).filename() == name) {
    throw InputError(SourceLocation{path}, "cannot write file: failed on purpose (TWINSIM_FAIL_WRITE)");
  }
}

}  // namespace twinsim
