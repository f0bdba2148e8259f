#include "backends/omni_backend_factory.h"

#include <algorithm>
#include <stdexcept>

#include "backends/learned/learned_omni_backend.h"
#include "sim/grouped_omni_backend.h"
#include "sim/newtonian_omni_backend.h"

namespace twinsim {

std::vector<std::string> AvailableOmniBackends() {
  std::vector<std::string> names = AvailableOmniEngines();
  names.push_back("learned");
  return names;
}

std::unique_ptr<OmniBackend> MakeOmniBackend(const std::string& name, const std::vector<OmniModel>& robots,
                                             const FieldModel& field, const FrameTiming& timing,
                                             const OmniBackendOptions& options) {
  if (name == "learned") return MakeLearnedOmniBackend(robots, timing, options.predictor);
  return MakeNewtonianOmniBackend(name, robots, field, timing);
}

std::unique_ptr<OmniBackend> MakeOmniBackend(const std::vector<RobotBackendChoice>& per_robot,
                                             const std::vector<OmniModel>& robots,
                                             const std::vector<std::string>& labels, const FieldModel& field,
                                             const FrameTiming& timing) {
  if (per_robot.size() != robots.size() || labels.size() != robots.size())
    throw std::invalid_argument("MakeOmniBackend: one backend and one label per robot expected");
  if (robots.empty()) throw std::invalid_argument("MakeOmniBackend: no robot");
  // Groups by backend and (learned only) predictor, in the order of their first robot.
  struct Group {
    RobotBackendChoice choice;
    std::vector<int> robots;
  };
  std::vector<Group> groups;
  for (std::size_t i = 0; i < per_robot.size(); ++i) {
    RobotBackendChoice c = per_robot[i];
    if (c.name != "learned") c.predictor.reset();
    auto same = [&](const Group& g) { return g.choice.name == c.name && g.choice.predictor == c.predictor; };
    auto it = std::find_if(groups.begin(), groups.end(), same);
    if (it == groups.end()) it = groups.insert(groups.end(), Group{c, {}});
    it->robots.push_back(static_cast<int>(i));
  }
  auto build = [&](const Group& g) {
    std::vector<OmniModel> models;
    for (int i : g.robots) models.push_back(robots[static_cast<std::size_t>(i)]);
    OmniBackendOptions options;
    options.predictor = g.choice.predictor;
    return MakeOmniBackend(g.choice.name, models, field, timing, options);
  };
  if (groups.size() == 1) return build(groups.front());
  std::vector<OmniBackendGroup> built;
  for (const Group& g : groups) built.push_back(OmniBackendGroup{build(g), g.robots});
  return std::make_unique<GroupedOmniBackend>(std::move(built), labels);
}

}  // namespace twinsim
