// Replay: predict every frame of a measured omni log 4 frames ahead with a model, as
// `twinsim replay` does, and print the error.
//   example_replay models/omni4.yaml LOG.csv [BACKEND]
#include <cstdio>
#include <exception>

#include "analysis/omni_replay.h"
#include "core/error.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s MODEL.yaml LOG.csv [BACKEND]\n", argv[0]);
    return 2;
  }
  try {
    const twinsim::OmniModel model = twinsim::LoadOmniModel(argv[1]);
    const twinsim::OmniLog log = twinsim::ReadOmniLog(argv[2]);
    twinsim::OmniReplayOptions options;
    options.backend = argc > 3 ? argv[3] : "analytic";
    options.horizon = 4;
    const twinsim::OmniReplayResult replay = twinsim::ReplayOmniLog(model, log, options);
    std::printf("%d of %zu frames predicted 4 frames ahead on %s: RMS position error %.4f m\n", replay.num_predicted(),
                log.rows.size(), options.backend.c_str(), twinsim::PositionRmse(log, replay));
    return 0;
  } catch (const twinsim::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
