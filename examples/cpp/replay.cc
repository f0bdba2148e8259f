// Replay: predict every frame of a measured omni log 4 frames ahead with a model, as
// `twinsim replay` does, and print the error.
//   example_replay models/omni4.yaml LOG.csv [BACKEND]
#include <cstdio>

#include "analysis/omni_replay.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 3, "MODEL.yaml LOG.csv [BACKEND]", [&] {
    const twinsim::OmniModel model = twinsim::LoadOmniModel(argv[1]);
    const twinsim::OmniLog log = twinsim::ReadOmniLog(argv[2]);
    twinsim::OmniReplayOptions options;
    options.backend = argc > 3 ? argv[3] : "analytic";
    options.horizon = 4;
    const twinsim::OmniReplayResult replay = twinsim::ReplayOmniLog(model, log, options);
    std::printf("%d of %zu frames predicted 4 frames ahead on %s: RMS position error %.4f m\n", replay.num_predicted(),
                log.rows.size(), options.backend.c_str(), twinsim::PositionRmse(log, replay));
  });
}
