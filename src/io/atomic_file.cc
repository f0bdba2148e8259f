#include "io/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "core/error.h"
#include "io/output_transaction.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

// Creates `folder` and its missing parents, telling `transaction` (if any) which ones
// it made.
void CreateFolders(const fs::path& folder, OutputTransaction* transaction) {
  std::error_code ec;
  std::vector<fs::path> missing;  // innermost first
  for (fs::path p = folder; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (fs::create_directory(*it, ec) && transaction != nullptr) transaction->NoteFolderCreated(it->string());
    if (ec) throw InputError(SourceLocation{it->string()}, "cannot create folder: " + ec.message());
  }
  if (!fs::is_directory(folder, ec)) {
    throw InputError(SourceLocation{folder.string()}, "cannot create folder: a file of that name is in the way");
  }
}

}  // namespace

void CheckFileCanBeWritten(const std::string& path) {
  const fs::path target(path);
  std::error_code ec;
  if (fs::is_directory(target, ec)) {
    throw InputError(SourceLocation{path}, "cannot write the file: a folder of that name is in the way");
  }
  for (fs::path p = target.parent_path(); !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, ec) && !fs::is_directory(p, ec))
      throw InputError(SourceLocation{p.string()}, "cannot create folder: a file of that name is in the way");
    if (p == p.parent_path()) break;
  }
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  const fs::path target(path);
  OutputTransaction* transaction = OutputTransaction::Current();
  if (target.has_parent_path()) CreateFolders(target.parent_path(), transaction);
  std::error_code ec;
  if (fs::is_directory(target, ec)) {
    throw InputError(SourceLocation{path}, "cannot write the file: a folder of that name is in the way");
  }
  MaybeFailWriteForTest(path);
  const fs::path temp = target.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(SourceLocation{path}, "cannot write file");
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      out.close();
      fs::remove(temp, ec);
      throw InputError(SourceLocation{path}, "write failed (disk full?)");
    }
  }
  if (transaction != nullptr) {
    transaction->Defer(temp.string(), path);
    return;
  }
  fs::rename(temp, target, ec);
  if (ec) {
    const std::string reason = ec.message();  // before remove() overwrites ec
    fs::remove(temp, ec);
    throw InputError(SourceLocation{path}, "cannot rename into place: " + reason);
  }
}

}  // namespace twinsim
