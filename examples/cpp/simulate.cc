// Simulate: load a scene, run it on a backend through the delay loop, print the path.
//   example_simulate scenes/drive45.yaml [ode|bullet|analytic]
#include <cstdio>

#include "scene/scene.h"
#include "scene/scene_run.h"

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 2, "SCENE.yaml [BACKEND]", [&] {
    const twinsim::Scene scene = twinsim::LoadScene(argv[1]);
    const twinsim::SimulationResult run = twinsim::RunOmniScene(scene, argc > 2 ? argv[2] : "analytic", "");
    for (std::size_t k = 0; k < run.frames[0].size(); k += 15) {
      const twinsim::FrameRecord& f = run.frames[0][k];
      std::printf("t = %5.2f s  x = %6.3f m  y = %6.3f m  theta = %6.3f rad\n", f.t, f.truth.x, f.truth.y, f.truth.theta);
    }
    std::printf("%s on %s: %.3f m driven\n", scene.name.c_str(), run.backend.c_str(), twinsim::TruePathLength(run, 0));
  });
}
