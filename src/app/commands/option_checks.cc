// The checks every command's options share, and the reading of arm logs at the cut-off
// --cutoff names (commands.h).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "app/commands/commands.h"
#include "analysis/derivative_cutoff.h"
#include "core/error.h"
#include "robots/arm/arm_log.h"
#include "robots/omni/omni_log.h"

namespace twinsim {
namespace {

// The value as a number, or false when the text is not one.
bool ParseNumber(const std::string& text, double* v) {
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}

}  // namespace

CLI::Validator PositiveNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!ParseNumber(text, &v)) return "expected a number, got '" + text + "'";
        return v > 0 && std::isfinite(v) ? std::string() : "must be a positive number, got " + text;
      },
      "POSITIVE", "positive");
}

CLI::Validator EnumWords(const std::vector<std::string>& words) {
  std::string list, braces;
  for (std::size_t k = 0; k < words.size(); ++k) {
    list += (k == 0 ? "" : k + 1 == words.size() ? " or " : ", ") + words[k];
    braces += (k == 0 ? "{" : ",") + words[k];
  }
  return CLI::Validator(
      [words, list](std::string& text) -> std::string {
        const auto at = std::find(words.begin(), words.end(), text);
        if (at == words.end()) return "must be " + list + ", got '" + text + "'";
        text = std::to_string(at - words.begin());  // what CLI11 reads into the enum
        return std::string();
      },
      braces + "}", "words");
}

CLI::Validator NonNegativeNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!ParseNumber(text, &v)) return "expected a number, got '" + text + "'";
        return v >= 0 && std::isfinite(v) ? std::string() : "must be a finite number >= 0, got " + text;
      },
      "NONNEGATIVE", "non-negative");
}

void CheckOptionValues(CLI::App* app) {
  for (CLI::Option* opt : app->get_options()) {
    const std::string type = opt->get_type_name();
    // Validators append their names to the type ("FLOAT:POSITIVE").
    if (type.rfind("FLOAT", 0) == 0) {
      // CLI11 reads "nan" and "inf" as doubles; no option means them.
      opt->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0;
            if (ParseNumber(text, &v) && !std::isfinite(v)) return "must be a finite number, got '" + text + "'";
            return {};
          },
          "", "finite"));
    } else if (type.rfind("TEXT", 0) == 0) {
      // No option means an empty text: an empty --out would name the current folder or
      // the file system's root, an empty --log no file.
      opt->check(CLI::Validator(
          [](std::string& text) -> std::string { return text.empty() ? "must not be empty" : std::string(); }, "",
          "not empty"));
    } else if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0) {
      // CLI11 holds a whole number beyond its type's range at the range's end (a seed of
      // 10^20 ran as 2^63 - 1) and wraps "-1" round to 2^64 - 1 for an unsigned one. Read
      // as CLI11 reads it (strtoll / strtoull, base 0: 0x.. too), then judged.
      const bool is_unsigned = type.rfind("UINT", 0) == 0;
      opt->check(CLI::Validator(
          [is_unsigned](std::string& text) -> std::string {
            if (is_unsigned && text.find('-') != std::string::npos) return "must not be negative, got " + text;
            errno = 0;
            if (is_unsigned) {
              std::strtoull(text.c_str(), nullptr, 0);
            } else {
              std::strtoll(text.c_str(), nullptr, 0);
            }
            if (errno == ERANGE)
              return std::string("must be within ") + (is_unsigned ? "0 to 18446744073709551615" : "+-9223372036854775807") +
                     ", got " + text;
            return std::string();
          },
          "", "whole"));
    }
  }
  for (CLI::App* sub : app->get_subcommands({})) CheckOptionValues(sub);
}

void AddLogSelectorOptions(CLI::App* cmd, OmniLogSelector* select) {
  cmd->add_option("--robot", select->robot,
                  "Omni log holding several robots: the robot id to read (column robot_id, robot or id)");
  cmd->add_option("--team", select->team, "Omni log holding several robots: the team to read (column team)");
}

OmniLog ReadOmniLogSayingHoles(const std::string& path, const OmniLogSelector& select) {
  OmniLog log = ReadOmniLog(path, select);
  // Said even with --quiet, on stderr: the rows a user counts are not the frames replayed.
  if (const std::string holes = DescribeClockHoles(log); !holes.empty()) std::fprintf(stderr, "note: %s\n", holes.c_str());
  return log;
}

void AddDrivingNoiseOption(CLI::App* cmd, std::string* value) {
  cmd->add_option("--driving-noise", *value,
                  "on: every robot slips by its model's driving noise (docs/models.md; a learned robot by its "
                  "predictor's where it has one); off: none; model: as each model's (or predictor's) "
                  "driving_noise.simulated says")
      ->check(CLI::IsMember({"on", "off", "model"}))
      ->capture_default_str();
}

void AddParameterUncertaintyOption(CLI::App* cmd, std::string* value, bool run) {
  cmd->add_option("--parameter-uncertainty", *value,
                  run ? "Omni, with --samples: on: samples 1.. of a learned robot each draw its predictor's own "
                        "uncertainty once (a linear predictor's weight_uncertainty or one network of its ensemble, "
                        "written by train) beside the driving noise; a physics robot draws the noise alone; off: the "
                        "noise alone"
                      : "Omni: on: the spread the model's identified parameters leave (observer.parameter_covariance, "
                        "written by identify; on the learned backend a linear predictor's weight_uncertainty or a "
                        "network's ensemble, written by train) widens each prediction's covariance and samples beside "
                        "the noise; off: the noise alone")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
}

void AddDerivativeCutoffOption(CLI::App* cmd, std::string* value) {
  cmd->add_option("--cutoff", *value,
                  "Arm: Hz, low-pass cut-off for qd/qdd derived from q, or auto: the lowest from 10 Hz up in octaves "
                  "whose derivatives let the identified model predict held-out torques within 5 % of the best")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0;
            if (text == "auto") return {};
            if (!ParseNumber(text, &v)) return "the cut-off must be auto or a number of Hz, got '" + text + "'";
            if (v > 0 && v <= 1e6) return {};
            return "the cut-off must be auto or a positive number of Hz up to 1e6, got " + text;
          },
          "auto|HZ", "cut-off"))
      ->capture_default_str();
}

std::vector<ArmLog> ReadArmLogsAtCutoff(const std::vector<std::string>& paths, const std::string& value,
                                        const ArmModel& model, const WlsIdentificationOptions& identification,
                                        double* cutoff_hz, std::string* brief) {
  ArmLogOptions log_options;
  const bool automatic = value == "auto";
  if (!automatic && !ParseNumber(value, &log_options.cutoff_hz)) {
    throw InputError("--cutoff: expected auto or a number of Hz, got '" + value + "'");
  }
  std::string why;
  if (!log_options.IsValid(&why)) throw InputError("--cutoff: " + why);
  std::vector<ArmLog> logs;
  for (const std::string& path : paths) {
    logs.push_back(ReadArmLog(path, log_options));
    CheckArmLogMatchesModel(logs.back(), model);
  }
  if (brief) brief->clear();
  if (automatic && !logs.empty()) {
    DerivativeCutoffOptions options;
    options.identification = identification;
    const DerivativeCutoffChoice choice = DeriveAtChosenCutoff(model, &logs, options);
    if (choice.cutoff_hz > 0) log_options.cutoff_hz = choice.cutoff_hz;
    if (brief) *brief = choice.Brief();
  }
  if (cutoff_hz) *cutoff_hz = log_options.cutoff_hz;
  return logs;
}

}  // namespace twinsim
