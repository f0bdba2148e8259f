#include "io/output_files.h"

#include <cstdio>

#include "io/atomic_file.h"

namespace twinsim {

std::string OutputFiles::Path(const std::string& name) const {
  return folder_.empty() ? name : folder_ + "/" + name;
}

void OutputFiles::Write(const std::string& name, const std::string& content) {
  const std::string path = Path(name);
  WriteFileAtomically(path, content);
  written_.push_back(path);
}

void OutputFiles::WritePng(const std::string& name, const RgbaImage& image) {
  const std::string path = Path(name);
  twinsim::WritePng(path, image);
  written_.push_back(path);
}

void OutputFiles::Add(const std::string& name) { written_.push_back(Path(name)); }

std::string OutputFiles::WroteList() const {
  std::string out = "wrote:\n";
  for (const std::string& path : written_) out += "  " + path + "\n";
  return out;
}

void OutputFiles::PrintWrote() const { std::fputs(WroteList().c_str(), stdout); }

}  // namespace twinsim
