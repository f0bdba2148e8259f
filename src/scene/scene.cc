#include "scene/scene.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/yaml_reader.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

bool ReadTwist(YamlMap& m, const std::string& key, Twist2* out) {
  std::vector<double> v;
  if (!m.Get(key, &v, 3)) return false;
  *out = Twist2{v[0], v[1], v[2]};
  return true;
}

void ReadCommands(const YAML::Node& node, const std::string& path, const std::string& context,
                  ErrorList* errors, CommandSpec* spec) {
  YamlMap m(node, path, context, errors);
  spec->line = m.Where().line;
  m.Require("type", &spec->type, std::vector<std::string>{"sequence", "test_drive", "figure_eight", "random", "go_to_pose"});
  const std::string& type = spec->type;
  if (type == "sequence") {
    m.Get("repeat", &spec->repeat, InRange(1, 1000000));
    YAML::Node segs = m.Child("segments");
    if (!segs.IsDefined()) {
      m.Missing("segments");
    } else if (!segs.IsSequence() || segs.size() == 0) {
      m.Error("segments", "expected a non-empty list of segments");
    } else {
      for (std::size_t i = 0; i < segs.size(); ++i) {
        YamlMap s(segs[i], path, context + ".segments[" + std::to_string(i) + "]", errors);
        CommandSpec::Segment seg;
        s.Require("duration", &seg.duration, Positive());
        const bool hold = s.Has("command"), ramp = s.Has("ramp_to");
        if (hold == ramp) s.Error("command", "give exactly one of 'command' (hold) or 'ramp_to' (ramp)");
        if (hold) ReadTwist(s, "command", &seg.command);
        if (ramp) seg.ramp = ReadTwist(s, "ramp_to", &seg.command);
        s.Finish();
        spec->segments.push_back(seg);
      }
    }
  } else if (type == "test_drive") {
    m.Get("start", &spec->start, NonNegative());
    m.Get("speed", &spec->speed, Positive());
    m.Get("direction_deg", &spec->direction_deg, InRange(-360, 360));
    m.Get("drive_time", &spec->drive_time, Positive());
  } else if (type == "figure_eight") {
    m.Get("start", &spec->start, NonNegative());
    m.Get("size", &spec->size, Positive());
    m.Get("period", &spec->period, Positive());
    m.Get("laps", &spec->laps, InRange(1, 1000));
  } else if (type == "random") {
    m.Get("max_speed", &spec->max_speed, Positive());
    m.Get("max_omega", &spec->max_omega, NonNegative());
    m.Get("min_segment", &spec->min_segment, Positive());
    m.Get("max_segment", &spec->max_segment, Positive());
    m.Get("rest_probability", &spec->rest_probability, InRange(0, 1));
    m.Get("ramp_probability", &spec->ramp_probability, InRange(0, 1));
    m.Get("rotate_probability", &spec->rotate_probability, InRange(0, 1));
    m.Get("leash", &spec->leash, NonNegative());
    m.Get("max_centripetal", &spec->max_centripetal, NonNegative());
    if (spec->max_segment < spec->min_segment) m.Error("max_segment", "must not be below min_segment");
  } else if (type == "go_to_pose") {
    m.Get("max_speed", &spec->max_speed, Positive());
    m.Get("max_omega", &spec->max_omega, Positive());
    m.Get("max_accel", &spec->max_accel, Positive());
    m.Get("gain", &spec->gain, Positive());
    m.Get("position_tolerance", &spec->position_tolerance, Positive());
    double angle_tolerance_deg = spec->angle_tolerance * 180 / kPi;
    if (m.Get("angle_tolerance_deg", &angle_tolerance_deg, Positive()))
      spec->angle_tolerance = angle_tolerance_deg * kPi / 180;
    m.Get("hold", &spec->hold, NonNegative());
    if (m.Get("predictor", &spec->predictor_path)) {
      std::filesystem::path p(spec->predictor_path);
      if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
      spec->predictor_path = p.lexically_normal().string();
      try {
        spec->predictor = std::make_shared<OmniPredictor>(OmniPredictor::Load(spec->predictor_path));
      } catch (const InputError& e) {
        errors->Add(e.what());
      }
    }
    YAML::Node targets = m.Child("targets");
    if (!targets.IsDefined()) {
      m.Missing("targets");
    } else if (!targets.IsSequence() || targets.size() == 0) {
      m.Error("targets", "expected a non-empty list of {x, y, theta_deg}");
    } else {
      for (std::size_t i = 0; i < targets.size(); ++i) {
        YamlMap t(targets[i], path, context + ".targets[" + std::to_string(i) + "]", errors);
        Pose2 p;
        double theta_deg = 0;
        t.Require("x", &p.x);
        t.Require("y", &p.y);
        t.Get("theta_deg", &theta_deg);
        p.theta = theta_deg * kPi / 180;
        t.Finish();
        spec->targets.push_back(p);
      }
    }
  }
  m.Finish();
}

Scene ReadScene(const YAML::Node& root, const std::string& path, const fs::path& base_dir,
                const YamlOverrides& plant = {}) {
  ErrorList errors;
  Scene scene;
  scene.path = path;
  YamlMap top(root, path, "", &errors);
  top.Require("name", &scene.name);
  top.Get("backend", &scene.backend, {"analytic", "ode", "bullet", "learned"});
  top.Get("frame_rate", &scene.frame_rate, InRange(1, 1000));
  top.Get("physics_substeps", &scene.physics_substeps, InRange(0, 1000));
  top.Require("duration", &scene.duration, InRange(1e-3, 24 * 3600));
  // Every frame of every robot is kept for the CSVs and plots.
  constexpr double kMaxFrames = 1e7;
  if (scene.duration * scene.frame_rate > kMaxFrames) {
    std::ostringstream msg;
    msg << "is " << scene.duration * scene.frame_rate << " frames at " << scene.frame_rate << " Hz; at most "
        << kMaxFrames << " are run";
    top.Error("duration", msg.str());
  }
  double seed = 1;
  if (top.Get("seed", &seed, InRange(0, 9007199254740992.0))) scene.seed = static_cast<std::uint64_t>(seed);

  if (top.Has("field")) {
    YamlMap f(top.Child("field"), path, "field", &errors);
    f.Get("length", &scene.field.length, Positive());
    f.Get("width", &scene.field.width, Positive());
    f.Get("wall_height", &scene.field.wall_height, Positive());
    f.Get("walls", &scene.field.walls);
    double slope_deg = 0, direction_deg = 0;
    if (f.Get("slope_deg", &slope_deg, InRange(0, 30))) scene.field.slope = slope_deg * kPi / 180;
    if (f.Get("slope_direction_deg", &direction_deg, InRange(-360, 360))) scene.field.slope_direction = direction_deg * kPi / 180;
    f.Finish();
  }

  YAML::Node robots = top.Child("robots");
  std::vector<SourceLocation> start_at;  // per robot, where its start is given
  if (!robots.IsDefined()) {
    top.Missing("robots");
  } else if (!robots.IsSequence() || robots.size() == 0) {
    top.Error("robots", "expected a non-empty list of robots");
  } else {
    std::set<std::string> names;
    std::vector<bool> id_given;                     // per robot
    std::vector<SourceLocation> id_at;              // per robot, where its team or id is given
    for (std::size_t i = 0; i < robots.size(); ++i) {
      const std::string context = "robots[" + std::to_string(i) + "]";
      YamlMap r(robots[i], path, context, &errors);
      SceneRobot robot;
      robot.name = "robot" + std::to_string(i);
      r.Get("name", &robot.name);
      if (!names.insert(robot.name).second) r.Error("name", "duplicate robot name '" + robot.name + "'");
      r.Get("team", &robot.team, {"blue", "yellow"});
      r.Get("present", &robot.present);
      id_given.push_back(r.Has("id"));
      id_at.push_back(r.Has("id") ? r.Where(r.Child("id")) : r.Where());
      robot.id = -1;
      if (id_given.back() && !r.Get("id", &robot.id, InRange(0, 15))) robot.id = -1;
      if (r.Require("model", &robot.model_path)) {
        fs::path p(robot.model_path);
        if (p.is_relative()) p = base_dir / p;
        robot.model_path = p.lexically_normal().string();
        try {
          robot.model = LoadOmniModel(robot.model_path, plant);
        } catch (const InputError& e) {
          errors.Add(e.what());
        }
      }
      start_at.push_back(r.Where());
      if (r.Has("start")) {
        YamlMap s(r.Child("start"), path, context + ".start", &errors);
        start_at.back() = s.Where();
        double theta_deg = 0;
        s.Get("x", &robot.start.x);
        s.Get("y", &robot.start.y);
        s.Get("theta_deg", &theta_deg);
        robot.start.theta = WrapAngle(theta_deg * kPi / 180);
        s.Finish();
      }
      if (r.Has("commands")) {
        ReadCommands(r.Child("commands"), path, context + ".commands", &errors, &robot.commands);
      } else {
        r.Missing("commands");
      }
      r.Finish();
      scene.robots.push_back(std::move(robot));
    }
    // Ids: the given ones unique within a team, the others the smallest free in order.
    std::map<std::pair<std::string, int>, std::size_t> taken;  // (team, id) -> robot
    for (std::size_t i = 0; i < scene.robots.size(); ++i) {
      const SceneRobot& robot = scene.robots[i];
      if (!id_given[i] || robot.id < 0) continue;
      auto [it, inserted] = taken.emplace(std::make_pair(robot.team, robot.id), i);
      if (!inserted) {
        errors.Add(id_at[i], "robots[" + std::to_string(i) + "]: " + robot.team + " robot id " +
                                 std::to_string(robot.id) + " is taken by robot '" + scene.robots[it->second].name +
                                 "'");
      }
    }
    for (std::size_t i = 0; i < scene.robots.size(); ++i) {
      SceneRobot& robot = scene.robots[i];
      if (id_given[i]) continue;
      int id = 0;
      while (taken.count({robot.team, id})) ++id;
      if (id > 15) {
        errors.Add(id_at[i], "robots[" + std::to_string(i) + "]: no " + robot.team + " robot id of 0..15 is left");
        continue;
      }
      robot.id = id;
      taken.emplace(std::make_pair(robot.team, id), i);
    }
  }
  std::optional<SourceLocation> ball_at;
  if (top.Has("ball")) {
    YamlMap b(top.Child("ball"), path, "ball", &errors);
    ball_at = b.Where();
    SceneBall ball;
    ReadBallModel(b, &ball.model);
    ball.start.position.z() = ball.model.radius;
    if (b.Has("start")) {
      YamlMap s(b.Child("start"), path, "ball.start", &errors);
      ball_at = s.Where();
      s.Get("x", &ball.start.position.x());
      s.Get("y", &ball.start.position.y());
      s.Get("z", &ball.start.position.z(), InRange(ball.model.radius, 10));
      s.Get("vx", &ball.start.velocity.x(), InRange(-20, 20));
      s.Get("vy", &ball.start.velocity.y(), InRange(-20, 20));
      s.Get("vz", &ball.start.velocity.z(), InRange(-20, 20));
      s.Finish();
    }
    b.Finish();
    scene.ball = ball;
  }
  scene.plots = ReadPlotSpecs(top, "plots");
  if (top.Has("tune_pid")) scene.tune_pid = top.Child("tune_pid");
  top.Finish();
  errors.ThrowIfAny();

  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    const SceneRobot& r = scene.robots[i];
    // Stamps jittered by more than an eighth of a frame either way would make the log
    // unreadable (rows land on frames by rounding, with 0.3 of a frame to spare).
    if (r.model.vision_time_jitter > 0.125 / scene.frame_rate) {
      std::ostringstream msg;
      msg << "robot '" << r.name << "': vision.time_jitter " << r.model.vision_time_jitter << " s is over an eighth of the "
          << scene.frame_rate << " Hz frame (" << 0.125 / scene.frame_rate << " s): its log would not be readable";
      errors.Add(SourceLocation{path}, msg.str());
    }
    if (r.commands.predictor) {
      const int delay = r.model.command_delay_frames + r.model.vision_delay_frames;
      try {
        r.commands.predictor->CheckUse(r.model, scene.frame_rate, delay, "go_to_pose of robot '" + r.name + "'");
        scene.robots[i].commands.predictor_model = std::make_shared<const OmniModel>(r.model);
      } catch (const InputError& e) {
        errors.Add(e.what());
      }
    }
    if (std::abs(r.start.x) > scene.field.length / 2 || std::abs(r.start.y) > scene.field.width / 2) {
      std::ostringstream msg;
      msg << "robot '" << r.name << "' starts at (" << r.start.x << ", " << r.start.y << ") m, outside the "
          << scene.field.length << " x " << scene.field.width << " m field";
      errors.Add(start_at[i], msg.str());
    }
  }
  if (scene.ball) {
    const Eigen::Vector3d& p = scene.ball->start.position;
    if (std::abs(p.x()) > scene.field.length / 2 - scene.ball->model.radius ||
        std::abs(p.y()) > scene.field.width / 2 - scene.ball->model.radius) {
      std::ostringstream msg;
      msg << "the ball starts at (" << p.x() << ", " << p.y() << ") m, outside the " << scene.field.length << " x "
          << scene.field.width << " m field";
      errors.Add(*ball_at, msg.str());
    }
  }
  errors.ThrowIfAny();
  return scene;
}

}  // namespace

FrameTiming Scene::timing() const {
  FrameTiming t;
  t.frame_rate = frame_rate;
  t.physics_substeps = physics_substeps > 0 ? physics_substeps : DefaultPhysicsSubsteps(frame_rate);
  return t;
}

int Scene::num_frames() const { return static_cast<int>(std::floor(duration * frame_rate + 1e-9)) + 1; }

Scene LoadScene(const std::string& path) { return LoadScene(path, SceneOverrides{}); }

Scene LoadScene(const std::string& path, const SceneOverrides& overrides) {
  const YAML::Node root = LoadYamlFile(path);
  return ReadScene(overrides.scene.empty() ? root : ApplyYamlOverrides(root, overrides.scene, path), path,
                   fs::path(path).parent_path(), overrides.plant);
}

Scene LoadSceneFromString(const std::string& yaml, const std::string& name, const std::string& base_dir) {
  YAML::Node root = LoadYamlString(yaml, name);
  if (!root.IsMap()) throw InputError(SourceLocation{name, 1}, "expected a YAML mapping at the top level");
  return ReadScene(root, name, base_dir);
}

std::string BallEngineFor(const std::string& backend) {
  const std::vector<std::string> engines = AvailableBallEngines();
  if (engines.empty()) throw InputError("the ball needs the ode or bullet engine; neither was compiled");
  if (backend == "ode" || backend == "bullet") return backend;
  return engines.front();
}

Simulation MakeSimulation(const Scene& scene, const std::string& backend, const OmniBackendOptions& options) {
  std::vector<OmniModel> models;
  std::vector<SimRobot> robots;
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    const SceneRobot& r = scene.robots[i];
    models.push_back(r.model);
    robots.push_back(SimRobot{r.name, r.model, r.start,
                              MakeCommandSource(r.commands, scene.seed, static_cast<int>(i), scene.duration, r.start),
                              r.present});
  }
  Simulation sim(std::move(robots), MakeOmniBackend(backend, models, scene.field, scene.timing(), options), scene.seed);
  if (scene.ball) {
    const std::string engine = BallEngineFor(backend);
    sim.AddBall(std::make_unique<BallField>(scene.ball->model, models, scene.field,
                                            MakeBallEngine(engine, scene.ball->model, models, scene.field)),
                scene.ball->start);
  }
  return sim;
}

}  // namespace twinsim
