// Reading a whole input file (a log, a model, a scene) into memory, with the checks every
// reader wants first: a folder given for a file, and a file too large to be what it claims
// refused before any memory is taken.
//
//   const std::string text = ReadInputFile("log.csv", "CSV", kMaxCsvBytes);
#pragma once

#include <cstdint>
#include <string>

namespace twinsim {

// The file's bytes. Throws InputError "path: ..." when `path` is a folder, holds more than
// `max_bytes` (`kind` names the format in the message: "CSV", "YAML") or cannot be opened.
std::string ReadInputFile(const std::string& path, const std::string& kind, std::uintmax_t max_bytes);

// `file` as named in an input file: relative to `base_dir` (the naming file's folder)
// unless absolute, normalised ("a/../b" -> "b").
std::string ResolveRelativeTo(const std::string& file, const std::string& base_dir);

}  // namespace twinsim
