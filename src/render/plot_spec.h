// The plots a scene asks `twinsim run` to draw: the `plots:` list of a scene file
// (docs/rendering.md), parsed into plain structs with defaults and checked like the rest
// of the scene (unknown keys, types and ranges reported as file:line:column).
//
//   plots:
//     - {type: path, file: path.png, source: both, region: [-2, 2, -1.5, 1.5],
//        orientation_every: 10, title: "drive45 on {backend}"}
#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "io/yaml_reader.h"
#include "render/plot.h"

namespace twinsim {

struct PlotSpec {
  std::string type = "path";      // path: robot paths on the field in metres
  std::string file;               // a plain file name ending in .png, written into the output folder
  std::string source;             // truth | seen | both; empty: both for one robot, truth for several
  int width = 1200;               // px
  int height = 900;               // px
  std::optional<WorldRect> region;  // m; absent: every path with a margin
  bool region_is_field = false;   // region: field (the field inside the walls)
  int orientation_every = -1;     // frames between heading ticks; 0: none; -1 (absent): automatic
  std::string title;              // "{scene}", "{backend}", "{seed}" are replaced; empty: "{scene} ({backend})"
};

// Reads the list under `key` of `parent` (absent: no plots). Every problem goes into
// parent's error list with its file:line:column; the result holds the valid entries.
std::vector<PlotSpec> ReadPlotSpecs(YamlMap& parent, const std::string& key);

// Reads a plot entry's required `file` into *file: a plain file name ending in .png
// (letters, digits, '.', '_', '-'; no folders) that no earlier plot of the same list
// (`taken`) writes. False, with the problem in m's error list, otherwise.
bool ReadPlotFile(YamlMap& m, std::set<std::string>* taken, std::string* file);

// The title with its placeholders filled in.
std::string PlotTitle(const PlotSpec& spec, const std::string& scene, const std::string& backend,
                      unsigned long long seed);

}  // namespace twinsim
