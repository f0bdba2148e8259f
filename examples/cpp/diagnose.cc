// Diagnose: find which effects an omni model misses in a log, add them and print the
// gap before and after, as `twinsim diagnose` does.
//   example_diagnose models/omni4.yaml LOG.csv
#include <cstdio>

#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 3, "MODEL.yaml LOG.csv", [&] {
    const twinsim::OmniModel model = twinsim::LoadOmniModel(argv[1]);
    twinsim::OmniModel repaired;
    const twinsim::DiagnosisReport report =
        twinsim::DiagnoseOmni(model, {twinsim::ReadOmniLog(argv[2])}, twinsim::DiagnosisOptions{}, &repaired, {});
    std::printf("%s", twinsim::FormatDiagnosisTable(report).c_str());
    std::printf("%s\n", twinsim::DiagnosisVerdict(report).c_str());
  });
}
