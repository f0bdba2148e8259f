#include "render/plot_spec.h"

#include <cctype>
#include <set>

namespace twinsim {
namespace {

// A plain file name: letters, digits, '.', '_', '-', not starting with '.', ending in .png.
bool PlainPngName(const std::string& name) {
  if (name.size() < 5 || name.front() == '.' || name.compare(name.size() - 4, 4, ".png") != 0) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) return false;
  return true;
}

void Replace(std::string* s, const std::string& from, const std::string& to) {
  for (std::size_t i = s->find(from); i != std::string::npos; i = s->find(from, i + to.size())) s->replace(i, from.size(), to);
}

}  // namespace

bool ReadPlotFile(YamlMap& m, std::set<std::string>* taken, std::string* file) {
  if (!m.Require("file", file)) return false;
  if (!PlainPngName(*file)) {
    m.Error("file", "expected a plain file name ending in .png (letters, digits, '.', '_', '-'; no folders), got '" +
                        *file + "'");
    return false;
  }
  if (!taken->insert(*file).second) {
    m.Error("file", "another plot already writes '" + *file + "'");
    return false;
  }
  return true;
}

std::vector<PlotSpec> ReadPlotSpecs(YamlMap& parent, const std::string& key) {
  std::vector<PlotSpec> specs;
  const YAML::Node list = parent.Child(key);
  if (!list.IsDefined() || list.IsNull()) return specs;
  if (!list.IsSequence()) {
    parent.Error(key, "expected a list of plots, e.g. [{type: path, file: path.png}]");
    return specs;
  }
  std::set<std::string> files;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string context = (parent.context().empty() ? "" : parent.context() + ".") + key + "[" + std::to_string(i) + "]";
    YamlMap m(list[i], parent.path(), context, parent.errors());
    if (!m.valid()) continue;
    PlotSpec spec;
    bool ok = m.Require("type", &spec.type, std::vector<std::string>{"path"});
    ok = ReadPlotFile(m, &files, &spec.file) && ok;
    m.Get("source", &spec.source, std::vector<std::string>{"truth", "seen", "both"});
    m.Get("width", &spec.width, InRange(240, 8192));
    m.Get("height", &spec.height, InRange(180, 8192));
    const YAML::Node region = m.Child("region");
    if (region.IsDefined() && !region.IsNull()) {
      if (region.IsScalar() && region.Scalar() == "field") {
        spec.region_is_field = true;
      } else {
        std::vector<double> r;
        if (!region.IsSequence()) {
          m.Error("region", "expected [x_min, x_max, y_min, y_max] in m, or 'field'");
          ok = false;
        } else if (m.Get("region", &r, 4)) {
          if (!(r[0] < r[1]) || !(r[2] < r[3])) {
            m.Error("region", "expected [x_min, x_max, y_min, y_max] with x_min < x_max and y_min < y_max");
            ok = false;
          } else {
            spec.region = WorldRect{r[0], r[1], r[2], r[3]};
          }
        }
      }
    }
    m.Get("orientation_every", &spec.orientation_every, InRange(0, 1000000));
    m.Get("title", &spec.title);
    m.Finish();
    if (ok) specs.push_back(std::move(spec));
  }
  return specs;
}

std::string PlotTitle(const PlotSpec& spec, const std::string& scene, const std::string& backend,
                      unsigned long long seed) {
  std::string title = spec.title.empty() ? "{scene} ({backend})" : spec.title;
  Replace(&title, "{scene}", scene);
  Replace(&title, "{backend}", backend);
  Replace(&title, "{seed}", std::to_string(seed));
  return title;
}

}  // namespace twinsim
