#include "backends/omni_backend_factory.h"

#include "backends/learned/learned_omni_backend.h"
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
  return std::make_unique<NewtonianOmniBackend>(MakeOmniEngine(name, robots, field), robots, timing);
}

}  // namespace twinsim
