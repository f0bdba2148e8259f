#include "io/append_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "core/error.h"

namespace twinsim {

AppendFile::AppendFile(std::string path) : path_(std::move(path)) {
  const std::filesystem::path target(path_);
  std::error_code ec;
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), ec);
  if (ec) throw InputError(SourceLocation{target.parent_path().string()}, "cannot create folder: " + ec.message());
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(SourceLocation{path_}, std::string("cannot write file: ") + std::strerror(errno));
}

AppendFile::~AppendFile() {
  if (fd_ >= 0) ::close(fd_);
}

AppendFile::AppendFile(AppendFile&& other) noexcept : path_(std::move(other.path_)), fd_(other.fd_) { other.fd_ = -1; }

AppendFile& AppendFile::operator=(AppendFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

void AppendFile::Append(const std::string& bytes) {
  const off_t end = ::lseek(fd_, 0, SEEK_CUR);  // where this append starts
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "nothing written";
      // Part of it in (a disk that filled up): the file goes back to its last whole append.
      if (end >= 0 && ::ftruncate(fd_, end) == 0) (void)::lseek(fd_, end, SEEK_SET);
      throw InputError(SourceLocation{path_}, "write failed: " + why);
    }
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace twinsim
