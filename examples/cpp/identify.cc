// Identify: estimate an arm's base inertial parameters and friction from logs, as
// `twinsim identify` does, and print each parameter a priori and identified.
//   example_identify models/rrr.yaml LOG.csv [LOG.csv ...]
#include <cstdio>
#include <vector>

#include "analysis/derivative_cutoff.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 3, "MODEL LOG.csv [LOG.csv ...]", [&] {
    const twinsim::ArmModel a_priori = twinsim::LoadArmModel(argv[1]);
    std::vector<twinsim::ArmLog> logs;
    for (int i = 2; i < argc; ++i) logs.push_back(twinsim::ReadArmLog(argv[i]));
    // The derivatives' cut-off chosen from the logs, as --cutoff auto does.
    std::printf("%s\n", twinsim::DeriveAtChosenCutoff(a_priori, &logs, {}).Brief().c_str());
    twinsim::WlsIdentificationSummary summary;
    const twinsim::ArmModel identified = twinsim::IdentifyArmByLeastSquares(a_priori, logs, {}, &summary);
    for (int k = 0; k < summary.base_parameters; ++k) {
      std::printf("%-28s a priori %10.4f  identified %10.4f  (%.1f %%)\n", summary.names[k].c_str(),
                  summary.a_priori[k], summary.consistent[k], summary.relative_std[k]);
    }
    std::printf("identified '%s' from %d samples\n", identified.name.c_str(), summary.samples);
  });
}
