#include "tuning/tuned_pid_yaml.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <sstream>

namespace twinsim {

std::string FormatTunedPidYaml(const TestRunEvaluator& evaluator, const PidTuningResult& r,
                               const std::string& out_dir) {
  namespace fs = std::filesystem;
  const SceneRobot& robot = evaluator.scene().robots[0];
  const OmniControllerModel c = WithPidParameters(robot.model.controller, r.best_parameters);
  const fs::path base = fs::absolute(robot.model_path);
  const fs::path rel = base.lexically_relative(fs::absolute(out_dir));

  std::ostringstream comment;
  comment.precision(10);
  comment << "PID parameters learned by `twinsim tune-pid " << evaluator.scene().path << "` on " << evaluator.backend()
          << "\n(policy gradient, seed 000 section 3.4): iteration " << r.search.best_iteration << " of "
          << r.iterations.size() << ", " << r.test_runs << " test runs.\n"
          << "Its test run: quality " << r.best_score.quality << ", distance " << r.best_score.distance
          << " m, average speed " << r.best_score.avg_speed << " m/s, end deviation " << r.best_score.end_deviation_pct
          << " %.";

  YAML::Emitter y;
  y.SetDoublePrecision(10);
  y << YAML::Comment(comment.str()) << YAML::BeginMap;
  y << YAML::Key << "extends" << YAML::Value << (rel.empty() ? base.string() : rel.string());
  y << YAML::Key << "name" << YAML::Value << robot.model.name + "_tuned";
  y << YAML::Key << "controller" << YAML::Value << YAML::BeginMap;
  const std::pair<const char*, const PidGains*> axes[] = {
      {"forward", &c.forward}, {"sideways", &c.sideways}, {"rotation", &c.rotation}};
  for (const auto& [name, g] : axes) {
    y << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "kp" << YAML::Value << g->kp << YAML::Key << "ki" << YAML::Value << g->ki;
    y << YAML::Key << "kd" << YAML::Value << g->kd << YAML::Key << "integral_limit" << YAML::Value << g->integral_limit;
    y << YAML::Key << "output_limit" << YAML::Value << g->output_limit << YAML::Key << "slew_rate" << YAML::Value
      << g->slew_rate;
    y << YAML::EndMap;
  }
  y << YAML::EndMap << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

}  // namespace twinsim
