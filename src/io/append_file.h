// A file written as a program runs, for logs of any length: each Append goes to the
// kernel in one write, so a reader (or whoever looks after a crash or `kill -9`) sees
// the file end on the last whole Append. Nothing is synced: a power cut may lose what
// the kernel had not written out yet.
//
// Unlike io/atomic_file.h, the file exists while it grows; a caller that appends whole
// lines (or whole frames of lines) leaves a file that always reads as a complete log
// of what ran.
//
//   AppendFile log("out/match/commands.csv");   // created, or emptied
//   log.Append("frame,t,robot,...\n");
#pragma once

#include <string>

namespace twinsim {

class AppendFile {
 public:
  // Creates `path` (and missing parent folders), or empties it. Throws InputError
  // naming the path when it cannot be created.
  explicit AppendFile(std::string path);
  ~AppendFile();
  AppendFile(AppendFile&& other) noexcept;
  AppendFile& operator=(AppendFile&& other) noexcept;
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;

  // Appends `bytes` (a short write is continued until all are in). Throws InputError
  // naming the path when the system refuses (disk full).
  void Append(const std::string& bytes);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace twinsim
