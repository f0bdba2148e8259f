// Writing output files so that a reader never sees half of one: the content goes to a
// temporary file in the same folder, which is renamed over the target when complete.
#pragma once

#include <string>

namespace twinsim {

// Writes `content` to `path` atomically; creates missing parent folders. Throws
// InputError when the folder cannot be created or written.
void WriteFileAtomically(const std::string& path, const std::string& content);

// Throws the InputError WriteFileAtomically(path, ...) would where a folder stands at
// `path` or a file where a folder of its path belongs; writes nothing. For commands
// that compute for minutes before they write.
void CheckFileCanBeWritten(const std::string& path);

}  // namespace twinsim
