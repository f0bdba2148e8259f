// Diagnose: find which effects an omni model misses in a log, add them and print the
// gap before and after, as `twinsim diagnose` does.
//   example_diagnose models/omni4.yaml LOG.csv
#include <cstdio>
#include <exception>

#include "core/error.h"
#include "diagnosis/diagnosis_report.h"
#include "diagnosis/omni_diagnosis.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s MODEL.yaml LOG.csv\n", argv[0]);
    return 2;
  }
  try {
    const twinsim::OmniModel model = twinsim::LoadOmniModel(argv[1]);
    twinsim::OmniModel repaired;
    const twinsim::DiagnosisReport report =
        twinsim::DiagnoseOmni(model, {twinsim::ReadOmniLog(argv[2])}, twinsim::DiagnosisOptions{}, &repaired, {});
    std::printf("%s", twinsim::FormatDiagnosisTable(report).c_str());
    std::printf("%s\n", twinsim::DiagnosisVerdict(report).c_str());
    return 0;
  } catch (const twinsim::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
