// The files a program writes into its output folder: each written atomically
// (io/atomic_file.h), every path remembered in order, and listed at the end as the
// commands list them:
//
//   wrote:
//     out/drive45/trajectory.csv
//     out/drive45/path.png
//
// Names are relative to the folder given at construction (none: names are paths).
// Files written by another writer (a predictor's Save, WriteOmniLog) are remembered
// with Add().
//
//   OutputFiles files("out/drive45");
//   files.Write("truth.csv", csv);
//   files.WritePng("path.png", image);
//   if (!quiet) files.PrintWrote();
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "io/png_image.h"

namespace twinsim {

class OutputFiles {
 public:
  OutputFiles() = default;
  explicit OutputFiles(std::string folder) : folder_(std::move(folder)) {}

  // folder/name, or name alone when there is no folder.
  std::string Path(const std::string& name) const;
  // Writes `content` to Path(name) atomically and remembers it. Throws InputError when
  // the file cannot be written.
  void Write(const std::string& name, const std::string& content);
  // Writes `image` as PNG to Path(name) atomically and remembers it. Throws InputError
  // when the file cannot be written.
  void WritePng(const std::string& name, const RgbaImage& image);
  // Remembers Path(name), written by another writer.
  void Add(const std::string& name);

  const std::string& folder() const { return folder_; }
  // Every path written or added, in order.
  const std::vector<std::string>& written() const { return written_; }
  // "wrote:\n" and a line "  path\n" per path.
  std::string WroteList() const;
  // Prints WroteList() to stdout.
  void PrintWrote() const;

 private:
  std::string folder_;
  std::vector<std::string> written_;
};

}  // namespace twinsim
