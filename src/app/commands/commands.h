// The twinsim command-line commands. Each Add*Command registers a CLI11 subcommand
// whose callback does the work and stores the process exit code in *exit_code;
// errors are thrown (core/error.h) and mapped to exit codes by main().
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace twinsim {

// Option checks with short messages (CLI11's own print the range up to 1.8e308 in full).
// A number option's value must be a number greater than zero / not below zero.
CLI::Validator PositiveNumber();
CLI::Validator NonNegativeNumber();
// An enum option's words, word k onto the enumerator of value k; any other word refused
// ("must be a, b or c, got 'd'").
CLI::Validator EnumWords(const std::vector<std::string>& words);
// Every number option is finite, an unsigned one (a seed) is not negative, and a text
// option (a path, a name) is not empty; applied to all options of `app` and its
// subcommands by main().
void CheckOptionValues(CLI::App* app);

// --robot ID and --team TEAM: which robot of an omni log holding several to read
// (robots/omni/omni_log.h).
struct OmniLogSelector;
void AddLogSelectorOptions(CLI::App* cmd, OmniLogSelector* select);
// ReadOmniLog, and a note on stderr where the log's clock has holes (frames the logger
// never wrote, read as frames without a measurement): said once per log read.
struct OmniLog;
OmniLog ReadOmniLogSayingHoles(const std::string& path, const OmniLogSelector& select);

// --driving-noise on|off|model: whether every omni robot of a scene slips by its model's
// driving noise (docs/models.md), or as each model's driving_noise.simulated says; the
// value goes into Scene::driving_noise, which MakeSimulation applies.
void AddDrivingNoiseOption(CLI::App* cmd, std::string* value);

// --parameter-uncertainty on|off: whether an omni model's parameters' covariance
// (observer.parameter_covariance, identify's) spreads its predictions besides its noise
// (analysis/omni_replay.h, OmniReplayOptions::parameter_shifts); `run`'s help (with --samples) says
// what its samples draw.
void AddParameterUncertaintyOption(CLI::App* cmd, std::string* value, bool run = false);

// --cutoff auto|HZ: the low-pass cut-off for an arm log's qd/qdd derived from q
// (robots/arm/arm_log.h); auto (the default) chooses it from the logs
// (analysis/derivative_cutoff.h).
void AddDerivativeCutoffOption(CLI::App* cmd, std::string* value);
// The arm logs at `paths`, each checked against `model`, derived at the cut-off `value`
// names: a number of Hz, or auto, chosen for `model` identified with `identification`.
// *cutoff_hz (if given) receives the cut-off used (Hz), *brief (if given) a line saying
// how auto chose it (empty for a number). Throws InputError.
struct ArmLog;
struct ArmModel;
struct WlsIdentificationOptions;
std::vector<ArmLog> ReadArmLogsAtCutoff(const std::vector<std::string>& paths, const std::string& value,
                                        const ArmModel& model, const WlsIdentificationOptions& identification,
                                        double* cutoff_hz = nullptr, std::string* brief = nullptr);

void AddRunCommand(CLI::App& app, int* exit_code);
void AddReplayCommand(CLI::App& app, int* exit_code);
void AddTrainCommand(CLI::App& app, int* exit_code);
void AddCompareCommand(CLI::App& app, int* exit_code);
void AddRegressCommand(CLI::App& app, int* exit_code);
void AddTunePidCommand(CLI::App& app, int* exit_code);
void AddExciteCommand(CLI::App& app, int* exit_code);
void AddIdentifyCommand(CLI::App& app, int* exit_code);
void AddIlcCommand(CLI::App& app, int* exit_code);
void AddDiagnoseCommand(CLI::App& app, int* exit_code);
void AddBatchCommand(CLI::App& app, int* exit_code);
void AddServeCommand(CLI::App& app, int* exit_code);

}  // namespace twinsim
