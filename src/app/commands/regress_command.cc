// `twinsim regress --golden DIR --candidate DIR [--tolerance METRES]`
#include <cstdio>
#include <memory>

#include "analysis/regress.h"
#include "app/commands/commands.h"
#include "core/error.h"

namespace twinsim {
namespace {

struct RegressCliOptions {
  std::string golden;
  std::string candidate;
  RegressOptions regress;
  bool quiet = false;
};

int Regress(const RegressCliOptions& options) {
  std::string invalid;
  if (!options.regress.IsValid(&invalid)) throw InputError("regress: bad option: " + invalid);
  const RegressSummary summary = RegressFolders(options.golden, options.candidate, options.regress);
  // The report goes out in full before the exit status says what it found.
  if (options.quiet)
    std::printf("%s\n", summary.BriefReport().c_str());
  else
    std::printf("%s", summary.FullReport().c_str());
  std::fflush(stdout);
  return summary.regression ? kExitCheckFailed : kExitOk;
}

}  // namespace

void AddRegressCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<RegressCliOptions>();
  CLI::App* cmd = app.add_subcommand("regress", "Compare a run's trajectories and plots with a golden run's.");
  cmd->footer(
      "Compares the top level of both folders (see docs/regression.md):\n"
      "  trajectory*.csv, truth*.csv  frame by frame: max and RMS position distance, max heading change\n"
      "  *.png                        pixel by pixel: pixels changed beyond the threshold, their fraction\n"
      "A regression (exit 1): a path moved more than --tolerance at some frame; a golden frame, trajectory\n"
      "or PNG missing from the candidate; a PNG that changed size; and, only when the option is given, a\n"
      "heading beyond --heading-tolerance or a PNG changed in more than --pixel-tolerance of its pixels.\n"
      "Files and frames only in the candidate, and changes within the tolerances, are reported only.\n"
      "Exit 0 otherwise, 2 on bad input.\n"
      "Writes into CANDIDATE/regress/ (its old PNGs removed first): NAME.png, a changed plot dimmed to grey\n"
      "with its changed pixels in magenta; NAME.csv.png, a moved path over the golden one (grey), with the\n"
      "distance against time below and the tolerance dashed.");
  cmd->add_option("--golden", options->golden, "Folder of the reference run")->required()->type_name("DIR");
  cmd->add_option("--candidate", options->candidate, "Folder of the run to check (regress/ is written here)")
      ->required()
      ->type_name("DIR");
  cmd->add_option("--tolerance", options->regress.tolerance, "How far a path may move at any frame (m)")
      ->capture_default_str()
      ->type_name("METRES");
  cmd->add_option("--heading-tolerance", options->regress.heading_tolerance,
                  "How far the heading may turn at any frame (rad; default: reported, never a regression)")
      ->type_name("RAD");
  cmd->add_option("--pixel-threshold", options->regress.pixel_threshold,
                  "Channel change (of 255) up to which a pixel counts as the same")
      ->capture_default_str()
      ->type_name("LEVELS");
  cmd->add_option("--pixel-tolerance", options->regress.pixel_tolerance,
                  "Fraction of a plot's pixels that may change (default: reported, never a regression)")
      ->type_name("FRACTION");
  cmd->add_flag("--quiet,-q", options->quiet, "Print the one-line verdict only");
  cmd->callback([options, exit_code] { *exit_code = Regress(*options); });
}

}  // namespace twinsim
