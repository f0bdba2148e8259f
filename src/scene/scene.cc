#include "scene/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "core/engine_names.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "io/input_file.h"
#include "io/yaml_reader.h"
#include "robots/omni/omni_log.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

bool ReadTwist(YamlMap& m, const std::string& key, Twist2* out) {
  std::vector<double> v;
  if (!m.Get(key, &v, 3)) return false;
  // A command the scene's own log could not hold (omni_log.h) is a typo.
  if (std::abs(v[0]) > kMaxSpeedCommand || std::abs(v[1]) > kMaxSpeedCommand || std::abs(v[2]) > kMaxTurnCommand) {
    std::ostringstream msg;
    msg << "must be at most " << kMaxSpeedCommand << " m/s (vx, vy) and " << kMaxTurnCommand << " rad/s (omega), got [" << v[0]
        << ", " << v[1] << ", " << v[2] << "]";
    m.Error(key, msg.str());
    return false;
  }
  *out = Twist2{v[0], v[1], v[2]};
  return true;
}

void ReadCommands(const YAML::Node& node, const std::string& path, const std::string& context,
                  ErrorList* errors, CommandSpec* spec) {
  YamlMap m(node, path, context, errors);
  spec->line = m.Where().line;
  m.Require("type", &spec->type,
            std::vector<std::string>{"sequence", "test_drive", "figure_eight", "random", "go_to_pose", "log"});
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
    m.Get("speed", &spec->speed, Positive(kMaxSpeedCommand));
    m.Get("direction_deg", &spec->direction_deg, InRange(-360, 360));
    m.Get("drive_time", &spec->drive_time, Positive());
  } else if (type == "figure_eight") {
    m.Get("start", &spec->start, NonNegative());
    m.Get("size", &spec->size, Positive());
    m.Get("period", &spec->period, Positive());
    m.Get("laps", &spec->laps, InRange(1, 1000));
    // Its field velocity (a w cos wt, a w cos 2wt), w = 2 pi / period, peaks at sqrt(2) a w.
    const double peak = std::sqrt(2.0) * spec->size * 2 * kPi / spec->period;
    if (peak > kMaxSpeedCommand) {
      std::ostringstream msg;
      msg << "size " << spec->size << " m in a period of " << spec->period << " s asks up to " << peak
          << " m/s; a command may be at most " << kMaxSpeedCommand << " m/s";
      m.Error("size", msg.str());
    }
  } else if (type == "random") {
    m.Get("max_speed", &spec->max_speed, Positive(kMaxSpeedCommand));
    m.Get("max_omega", &spec->max_omega, NonNegative(kMaxTurnCommand));
    m.Get("min_segment", &spec->min_segment, Positive());
    m.Get("max_segment", &spec->max_segment, Positive());
    m.Get("rest_probability", &spec->rest_probability, InRange(0, 1));
    m.Get("ramp_probability", &spec->ramp_probability, InRange(0, 1));
    m.Get("rotate_probability", &spec->rotate_probability, InRange(0, 1));
    m.Get("leash", &spec->leash, NonNegative());
    m.Get("max_centripetal", &spec->max_centripetal, NonNegative());
    if (spec->max_segment < spec->min_segment) m.Error("max_segment", "must not be below min_segment");
  } else if (type == "log") {
    // Read when the scene's frame rate and the robot's name are known (ReadScene).
    if (m.Require("file", &spec->log_path)) {
      spec->log_path = ResolveRelativeTo(spec->log_path, fs::path(path).parent_path().string());
    }
    m.Get("robot", &spec->log_robot);
  } else if (type == "go_to_pose") {
    m.Get("max_speed", &spec->max_speed, Positive(kMaxSpeedCommand));
    m.Get("max_omega", &spec->max_omega, Positive(kMaxTurnCommand));
    m.Get("max_accel", &spec->max_accel, Positive());
    m.Get("gain", &spec->gain, Positive());
    m.Get("position_tolerance", &spec->position_tolerance, Positive());
    double angle_tolerance_deg = spec->angle_tolerance * 180 / kPi;
    if (m.Get("angle_tolerance_deg", &angle_tolerance_deg, Positive()))
      spec->angle_tolerance = angle_tolerance_deg * kPi / 180;
    m.Get("hold", &spec->hold, NonNegative());
    if (m.Get("predictor", &spec->predictor_path)) {
      spec->predictor_path = ResolveRelativeTo(spec->predictor_path, fs::path(path).parent_path().string());
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

// Where a robot's `backend:` and `predictor:` are given (the robot's mapping when absent).
struct RobotBackendAt {
  SourceLocation backend;
  SourceLocation predictor;
};

// Reads a robot's own `backend:` and `predictor:` (loaded once per file: robots naming
// the same file share it, and so one learned backend). The checks that need the whole
// scene are CheckRobotBackend's.
void ReadRobotBackend(YamlMap& r, const fs::path& base_dir,
                      std::map<std::string, std::shared_ptr<const OmniPredictor>>* predictors, SceneRobot* robot,
                      std::vector<RobotBackendAt>* at) {
  RobotBackendAt where{r.Where(), r.Where()};
  if (r.Has("backend")) {
    where.backend = r.Where(r.Child("backend"));
    if (r.Get("backend", &robot->backend, KnownBackends())) {
      const std::vector<std::string> built = AvailableOmniBackends();
      if (std::find(built.begin(), built.end(), robot->backend) == built.end()) {
        std::string upper = robot->backend;
        for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        r.Error("backend", robot->backend + " backend not compiled; rebuild with -DTWINSIM_WITH_" + upper + "=ON");
        robot->backend.clear();
      }
    }
  }
  if (r.Has("predictor")) {
    where.predictor = r.Where(r.Child("predictor"));
    if (r.Get("predictor", &robot->predictor_path)) {
      robot->predictor_path = ResolveRelativeTo(robot->predictor_path, base_dir.string());
      auto it = predictors->find(robot->predictor_path);
      if (it == predictors->end()) {
        std::shared_ptr<const OmniPredictor> loaded;
        try {
          loaded = std::make_shared<const OmniPredictor>(OmniPredictor::Load(robot->predictor_path));
        } catch (const InputError& e) {
          r.errors()->Add(where.predictor, "'predictor' in '" + r.context() + "': " + e.what());
        }
        it = predictors->emplace(robot->predictor_path, loaded).first;
      }
      robot->predictor = it->second;
    }
  }
  at->push_back(where);
}

// One camera of `cameras: {list: [...]}` (scene/camera_layout.h).
CameraPlacement ReadCameraPlacement(const YAML::Node& node, const std::string& path, const std::string& context,
                                    const FieldModel& field, ErrorList* errors) {
  YamlMap m(node, path, context, errors);
  CameraPlacement p;
  std::vector<double> position, fov, area;
  if (m.Require("position", &position, 2, InRange(-100, 100))) p.position = Eigen::Vector2d(position[0], position[1]);
  m.Get("height", &p.height, InRange(1, 20));
  const bool has_fov = m.Get("field_of_view", &fov, 2, InRange(1, 170));
  if (has_fov) p.field_of_view = Eigen::Vector2d(fov[0], fov[1]);
  bool has_area = m.Get("area", &area, 4, InRange(-100, 100));
  if (has_area) {
    p.area_low = Eigen::Vector2d(area[0], area[1]);
    p.area_high = Eigen::Vector2d(area[2], area[3]);
    if (area[0] >= area[2] || area[1] >= area[3]) {
      m.Error("area", "expected [x_low, y_low, x_high, y_high] with low < high");
      has_area = false;
    }
  }
  bool one = true;  // of the field of view and the area
  if (m.valid() && !m.Has("field_of_view") && !m.Has("area")) {
    m.Error("field_of_view", "a camera needs its field_of_view (degrees across x and y) or the area it sees");
  } else if (m.Has("field_of_view") && m.Has("area")) {
    m.Error("area", "give the field_of_view or the area, not both");
    one = false;
  }
  m.Finish();
  if (m.valid() && one && (has_fov || has_area)) {
    const CameraView v = PlacedCamera(p, field);
    if (!(v.low.x() < v.high.x() && v.low.y() < v.high.y())) {
      std::ostringstream msg;
      msg << context << " sees nothing inside the walls (" << field.length << " x " << field.width << " m)";
      errors->Add(m.Where(), msg.str());
    }
  }
  return p;
}

// The scene's `cameras:` (scene/camera_layout.h): a grid, a league layout or a list.
CameraSetup ReadCameras(const YAML::Node& node, const std::string& path, const FieldModel& field,
                        ErrorList* errors) {
  YamlMap c(node, path, "cameras", errors);
  CameraSetup setup;
  std::string layout, capture = "synchronous";
  if (c.Get("layout", &layout, LeagueCameraLayoutNames())) setup.grid = *LeagueCameraLayout(layout);
  c.Get("columns", &setup.grid.columns, InRange(1, 8));
  c.Get("rows", &setup.grid.rows, InRange(1, 8));
  c.Get("overlap", &setup.grid.overlap, InRange(0, 3));
  c.Get("height", &setup.grid.height, InRange(1, 20));
  c.Get("capture", &capture, {"synchronous", "staggered"});
  setup.staggered = capture == "staggered";
  const bool grid_keys = c.Has("columns") || c.Has("rows") || c.Has("overlap") || c.Has("height");
  if (c.Has("layout") && grid_keys) c.Error("layout", "a layout is a grid of its own: give it or columns/rows/overlap/height");
  if (node.IsMap() && node["list"].IsDefined() && node["list"].IsNull()) {
    c.Child("list");
    c.Error("list", "expected a list of 1 to 16 cameras, got nothing");  // not one camera by default
  } else if (c.Has("list")) {
    const YAML::Node list = c.Child("list");
    if (c.Has("layout") || grid_keys) c.Error("list", "listed cameras take no layout or grid keys (columns, rows, overlap, height)");
    if (!list.IsSequence() || list.size() == 0 || list.size() > 16) {
      c.Error("list", "expected a list of 1 to 16 cameras");
    } else {
      for (std::size_t i = 0; i < list.size(); ++i)
        setup.placements.push_back(ReadCameraPlacement(list[i], path, "camera " + std::to_string(i), field, errors));
    }
  }
  c.Finish();
  return setup;
}

// A robot's backend against the rest of the scene: a learned robot has a predictor that
// fits its model and the frame rate (as the learned backend checks it), and a predictor
// belongs to a learned robot.
void CheckRobotBackend(const Scene& scene, std::size_t i, const RobotBackendAt& at, ErrorList* errors) {
  const SceneRobot& r = scene.robots[i];
  const std::string context = "robots[" + std::to_string(i) + "]";
  if (r.predictor_path.empty()) {
    if (r.backend == "learned") {
      errors->Add(at.backend, "'backend' in '" + context + "': robot '" + r.name +
                                  "' on the learned backend needs 'predictor': a 1-frame predictor file "
                                  "(twinsim train --horizon 1)");
    }
    return;
  }
  if (r.backend != "learned") {
    errors->Add(at.predictor, "'predictor' in '" + context + "': applies to 'backend: learned' only; robot '" +
                                  r.name + "' " +
                                  (r.backend.empty() ? "names no backend of its own" : "runs on " + r.backend));
    return;
  }
  if (!r.predictor) return;  // did not load: said above
  try {
    r.predictor->CheckUse(r.model, scene.frame_rate, 1, "the learned backend of robot '" + r.name + "'");
  } catch (const InputError& e) {
    errors->Add(at.predictor, "'predictor' in '" + context + "': " + e.what());
  }
}

Scene ReadScene(const YAML::Node& root, const std::string& path, const fs::path& base_dir,
                const YamlOverrides& plant = {}) {
  ErrorList errors;
  Scene scene;
  scene.path = path;
  YamlMap top(root, path, "", &errors);
  top.Require("name", &scene.name);
  top.Get("backend", &scene.backend, KnownBackends());
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
  std::vector<RobotBackendAt> backend_at;  // per robot, where its backend keys are given
  if (!robots.IsDefined()) {
    top.Missing("robots");
  } else if (!robots.IsSequence() || robots.size() == 0) {
    top.Error("robots", "expected a non-empty list of robots");
  } else {
    std::set<std::string> names;
    std::map<std::string, std::shared_ptr<const OmniPredictor>> predictors;  // by resolved path
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
        robot.model_path = ResolveRelativeTo(robot.model_path, base_dir.string());
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
        CommandSpec& spec = robot.commands;
        if (spec.type == "log" && !spec.log_path.empty()) {
          if (spec.log_robot.empty()) spec.log_robot = robot.name;
          try {
            spec.log = std::make_shared<CommandLog>(ReadCommandLog(spec.log_path, spec.log_robot, scene.frame_rate));
          } catch (const InputError& e) {
            errors.Add(SourceLocation{path, spec.line}, context + ".commands: " + e.what());
          }
        }
      } else {
        r.Missing("commands");
      }
      ReadRobotBackend(r, base_dir, &predictors, &robot, &backend_at);
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
    if (b.Has("vision")) {
      YamlMap v(b.Child("vision"), path, "ball.vision", &errors);
      v.Get("noise_xy", &ball.vision.noise_xy, InRange(0, 1));
      v.Get("noise_z", &ball.vision.noise_z, InRange(0, 1));
      v.Get("drop_probability", &ball.vision.drop_probability, InRange(0, 1));
      v.Finish();
    }
    b.Finish();
    scene.ball = ball;
  }
  if (top.Has("cameras")) scene.cameras = ReadCameras(top.Child("cameras"), path, scene.field, &errors);
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
    CheckRobotBackend(scene, i, backend_at[i], &errors);
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

void ReplayCommandLog(const std::string& path, Scene* scene) {
  // A robot that starts off the field stays off in a run (only a served field's
  // teleports add robots), so it needs no rows.
  std::vector<std::string> names;
  std::vector<SceneRobot*> robots;
  for (SceneRobot& r : scene->robots) {
    if (!r.present) continue;
    names.push_back(r.name);
    robots.push_back(&r);
  }
  std::vector<CommandSpec> specs = LogCommandSpecs(path, names, scene->frame_rate);
  int last = 0;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    last = std::max(last, specs[i].log->frames.back());
    robots[i]->commands = std::move(specs[i]);
  }
  scene->duration = last / scene->frame_rate;
}

std::vector<std::string> RobotBackends(const Scene& scene, const std::string& field_backend) {
  std::vector<std::string> names;
  for (const SceneRobot& r : scene.robots) names.push_back(r.backend.empty() ? field_backend : r.backend);
  return names;
}

std::string BallEngineFor(const std::string& backend) {
  const std::vector<std::string> engines = AvailableBallEngines();
  if (engines.empty()) throw InputError("the ball needs the ode or bullet engine; neither was compiled");
  if (backend == "ode" || backend == "bullet") return backend;
  return engines.front();
}

std::string BallEngineFor(const std::vector<std::string>& backends) {
  for (const char* engine : {"ode", "bullet"})
    if (std::find(backends.begin(), backends.end(), engine) != backends.end()) return BallEngineFor(engine);
  return BallEngineFor(std::string("analytic"));
}

RobotBackendChoice RobotChoice(const SceneRobot& robot, const std::string& backend, const OmniBackendOptions& options) {
  // A robot of its own backend brings its own predictor; the others share the field's.
  return robot.backend.empty() ? RobotBackendChoice{backend, options.predictor}
                               : RobotBackendChoice{robot.backend, robot.predictor};
}

OmniModel SimulatedRobotModel(const Scene& scene, const SceneRobot& robot, const RobotBackendChoice& choice) {
  OmniModel model = robot.model;
  if (choice.name == "learned") model.driving_noise = LearnedDrivingNoise(robot.model, choice.predictor.get());
  if (scene.driving_noise != "model") model.driving_noise.simulated = scene.driving_noise == "on";
  return model;
}

Simulation MakeSimulation(const Scene& scene, const std::string& backend, const OmniBackendOptions& options,
                          const CommandSourceFactory& commands) {
  std::vector<OmniModel> models;
  std::vector<SimRobot> robots;
  std::vector<RobotBackendChoice> choices;
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    const SceneRobot& r = scene.robots[i];
    const RobotBackendChoice choice = RobotChoice(r, backend, options);
    // The backend simulates the model itself; the simulation loop draws the noise.
    models.push_back(r.model);
    robots.push_back(SimRobot{r.name, SimulatedRobotModel(scene, r, choice), r.start,
                              commands ? commands(i)
                                       : MakeCommandSource(r.commands, scene.seed, static_cast<int>(i), scene.duration,
                                                           r.start),
                              r.present});
    choices.push_back(choice);
    labels.push_back(r.name);
  }
  // Where robots name their own backends, say which robots need the field's predictor
  // (the learned backend's own message cannot tell them apart).
  const auto own = [](const SceneRobot& r) { return !r.backend.empty(); };
  if (backend == "learned" && !options.predictor && std::any_of(scene.robots.begin(), scene.robots.end(), own)) {
    std::string names;
    for (const SceneRobot& r : scene.robots)
      if (!own(r)) names += (names.empty() ? "'" : ", '") + r.name + "'";
    if (!names.empty()) {
      throw InputError(SourceLocation{scene.path},
                       "the learned backend needs a predictor: pass --predictor FILE (robots " + names +
                           " run on the field's backend, learned; a robot's own 'backend: learned' takes 'predictor:')");
    }
  }
  Simulation sim(std::move(robots), MakeOmniBackend(choices, models, labels, scene.field, scene.timing()), scene.seed);
  if (scene.ball) {
    const std::string engine = BallEngineFor(RobotBackends(scene, backend));
    sim.AddBall(std::make_unique<BallField>(scene.ball->model, models, scene.field,
                                            MakeBallEngine(engine, scene.ball->model, models, scene.field)),
                scene.ball->start, scene.ball->vision);
  }
  return sim;
}

}  // namespace twinsim
