// Loads the shipped four-wheel model, drives it one second straight ahead on the
// analytic backend through the delay loop, and checks it moved forward.
#include <cstdio>
#include <memory>

#include "backends/omni_backend_factory.h"
#include "robots/omni/omni_model.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const twinsim::OmniModel model = twinsim::LoadOmniModel(argv[1]);
  twinsim::CommandSpec spec;
  spec.type = "sequence";
  spec.segments = {{1.0, twinsim::Twist2{1.0, 0, 0}, false}};
  std::vector<twinsim::SimRobot> robots;
  robots.push_back({"r", model, twinsim::Pose2{}, twinsim::MakeCommandSource(spec, 1, 0, 1.0, twinsim::Pose2{})});
  twinsim::Simulation sim(std::move(robots),
                          twinsim::MakeOmniBackend("analytic", {model}, twinsim::FieldModel{}, twinsim::FrameTiming{}), 1);
  const twinsim::SimulationResult run = sim.Run(31);
  const double x = run.frames[0].back().truth.x;
  std::printf("drove %.3f m in 1 s\n", x);
  return x > 0.3 && x < 1.0 ? 0 : 1;
}
