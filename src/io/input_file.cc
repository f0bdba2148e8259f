#include "io/input_file.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace twinsim {

std::string ReadInputFile(const std::string& path, const std::string& kind, std::uintmax_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(SourceLocation{path}, "is a folder, not a " + kind + " file");
  const auto bytes = std::filesystem::file_size(path, ec);
  if (!ec && bytes > max_bytes) {
    throw InputError(SourceLocation{path}, "the file holds " + std::to_string(bytes >> 20) + " MiB; " + kind +
                                               " files above " + std::to_string(max_bytes >> 20) +
                                               " MiB are refused (split it)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(SourceLocation{path}, "cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string ResolveRelativeTo(const std::string& file, const std::string& base_dir) {
  std::filesystem::path p(file);
  if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
  return p.lexically_normal().string();
}

}  // namespace twinsim
