// The checks every command's options share (commands.h).
#include <cmath>
#include <cstdlib>
#include <string>

#include "app/commands/commands.h"
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

CLI::Validator NonNegativeNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!ParseNumber(text, &v)) return "expected a number, got '" + text + "'";
        return v >= 0 && std::isfinite(v) ? std::string() : "must be a finite number >= 0, got " + text;
      },
      "NONNEGATIVE", "non-negative");
}

void CheckNumberOptions(CLI::App* app) {
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
    } else if (type.rfind("UINT", 0) == 0) {
      // CLI11 wraps "-1" round to 2^64 - 1 for an unsigned option.
      opt->check(CLI::Validator(
          [](std::string& text) -> std::string {
            return text.find('-') == std::string::npos ? std::string() : "must not be negative, got " + text;
          },
          "", "unsigned"));
    }
  }
  for (CLI::App* sub : app->get_subcommands({})) CheckNumberOptions(sub);
}

void AddLogSelectorOptions(CLI::App* cmd, OmniLogSelector* select) {
  cmd->add_option("--robot", select->robot,
                  "Omni log holding several robots: the robot id to read (column robot_id, robot or id)");
  cmd->add_option("--team", select->team, "Omni log holding several robots: the team to read (column team)");
}

void AddDrivingNoiseOption(CLI::App* cmd, std::string* value) {
  cmd->add_option("--driving-noise", *value,
                  "on: every robot slips by its model's driving noise (docs/models.md; a learned robot by its "
                  "predictor's where it has one); off: none; model: as each model's (or predictor's) "
                  "driving_noise.simulated says")
      ->check(CLI::IsMember({"on", "off", "model"}))
      ->capture_default_str();
}

}  // namespace twinsim
