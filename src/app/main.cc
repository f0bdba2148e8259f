// twinsim: a simulator for robots that learns from measured data.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <glog/logging.h>

#include "app/commands/commands.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "io/output_transaction.h"


int main(int argc, char** argv) {
  using namespace twinsim;
  // Ceres logs through glog; a fit that steps outside an effect's range is handled (and
  // reported) by twinsim, so its solver's own complaints stay off the terminal.
  FLAGS_minloglevel = google::GLOG_FATAL;
  CLI::App app{"twinsim: simulate small-size omni robots on ODE, Bullet or an analytic model,\n"
               "with the on-board controller and the camera/command delay loop of a real game."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "twinsim 0.1.0");
  app.footer("Run 'twinsim COMMAND --help' for a command's options. Exit codes: 0 ok, 1 a check failed,\n"
             "2 bad input, 3 internal error.");
  int exit_code = kExitOk;
  AddRunCommand(app, &exit_code);
  AddReplayCommand(app, &exit_code);
  AddTrainCommand(app, &exit_code);
  AddCompareCommand(app, &exit_code);
  AddRegressCommand(app, &exit_code);
  AddTunePidCommand(app, &exit_code);
  AddExciteCommand(app, &exit_code);
  AddIdentifyCommand(app, &exit_code);
  AddIlcCommand(app, &exit_code);
  AddDiagnoseCommand(app, &exit_code);
  AddBatchCommand(app, &exit_code);
  AddServeCommand(app, &exit_code);
  CheckOptionValues(&app);
  // CLI11 says only "A subcommand is required" of a word that names none.
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::string names;
    for (const CLI::App* sub : app.get_subcommands({})) {
      known = known || sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr, "unknown command '%s' (the commands: %s); run 'twinsim --help'\n",
                   PrintableText(argv[1]).c_str(), names.c_str());
      return kExitBadInput;
    }
  }
  InstallInterruptHandlers();
  try {
    // A command's files appear together when it returns, or not at all (an error, Ctrl-C).
    OutputTransaction outputs;
    app.parse(argc, argv);
    ThrowIfInterrupted();
    outputs.Commit();
  } catch (const Interrupted& e) {
    std::fprintf(stderr, "%s\n", PrintableText(e.what()).c_str());
    return e.exit_code();
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", PrintableText(e.what()).c_str());
    return kExitBadInput;
  } catch (const CheckFailed& e) {
    std::fprintf(stderr, "%s\n", PrintableText(e.what()).c_str());
    return kExitCheckFailed;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "internal error: out of memory\n");
    return kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", PrintableText(e.what()).c_str());
    return kExitInternal;
  }
  return exit_code;
}
