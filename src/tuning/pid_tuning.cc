#include "tuning/pid_tuning.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "core/parallel.h"
#include "core/pose.h"
#include "io/yaml_reader.h"

namespace twinsim {

std::vector<std::string> PidParameterNames() {
  static const char* axes[] = {"forward", "sideways", "rotation"};
  static const char* params[] = {"kp", "ki", "kd", "integral_limit", "output_limit", "slew_rate"};
  std::vector<std::string> names;
  for (const char* a : axes)
    for (const char* p : params) names.push_back(std::string(a) + "." + p);
  return names;
}

Eigen::VectorXd PidParameters(const OmniControllerModel& c) {
  Eigen::VectorXd p(kPidParameters);
  p << c.forward.AsVector(), c.sideways.AsVector(), c.rotation.AsVector();
  return p;
}

OmniControllerModel WithPidParameters(OmniControllerModel c, const Eigen::VectorXd& p) {
  if (p.size() != kPidParameters) throw std::invalid_argument("a PID parameter set has 18 values");
  c.forward = PidGains::FromVector(p.segment<6>(0));
  c.sideways = PidGains::FromVector(p.segment<6>(6));
  c.rotation = PidGains::FromVector(p.segment<6>(12));
  return c;
}

Eigen::VectorXd DefaultPidScale() {
  OmniControllerModel defaults;
  Eigen::VectorXd s = PidParameters(defaults);
  s[2] = s[8] = 0.5;  // kd, N per m/s^2: a tenth of a frame's worth of kp
  s[14] = 0.005;      // rotation kd, N·m per rad/s^2
  return s;
}

TestRunScore ScoreTestRun(const std::vector<FrameRecord>& frames, const TestDrive& drive,
                          const QualityWeights& w) {
  // The camera's frames, each at the time it was captured.
  const double dt = 1 / drive.frame_rate;
  std::vector<std::pair<double, Pose2>> seen;
  for (const FrameRecord& f : frames)
    if (f.observed) seen.emplace_back(f.t - drive.vision_delay_frames * dt, f.seen);
  if (seen.empty()) throw InputError("test run: no frame was observed");
  const Pose2 p0 = seen.front().second;
  const double a = p0.theta + drive.direction;
  const Eigen::Vector2d u(std::cos(a), std::sin(a)), n(-std::sin(a), std::cos(a));
  auto offset = [&](const Pose2& p) { return Eigen::Vector2d(p.x - p0.x, p.y - p0.y); };

  // The stop command acts command_delay frames after it is sent.
  const double t_stop = drive.start + drive.drive_time + drive.command_delay_frames * dt;
  TestRunScore s;
  Pose2 stop_pose = p0;
  for (const auto& [t, p] : seen) {
    if (t <= t_stop + 1e-9) stop_pose = p;
    s.deviation = std::max(s.deviation, std::abs(offset(p).dot(n)));
    s.rotation = std::max(s.rotation, std::abs(WrapAngle(p.theta - p0.theta)));
  }
  const Pose2& end = seen.back().second;
  s.distance = offset(stop_pose).dot(u);
  s.stop_distance = std::hypot(end.x - stop_pose.x, end.y - stop_pose.y);
  s.avg_speed = s.distance / drive.drive_time;
  const double along = offset(end).dot(u);
  s.end_deviation_pct = std::abs(along) < 1e-3 ? 0 : 100 * std::abs(offset(end).dot(n)) / std::abs(along);
  s.quality = w.distance * s.distance - w.deviation * s.deviation - w.rotation * s.rotation -
              w.stop_distance * s.stop_distance;
  return s;
}

TestRunEvaluator::TestRunEvaluator(Scene scene, std::string backend, QualityWeights weights)
    : scene_(std::move(scene)), backend_(std::move(backend)), weights_(weights) {
  const SourceLocation where{scene_.path};
  if (scene_.robots.size() != 1)
    throw InputError(where, "a PID test run has exactly one robot, the scene has " +
                                std::to_string(scene_.robots.size()));
  const SceneRobot& r = scene_.robots[0];
  if (r.commands.type != "test_drive")
    throw InputError(SourceLocation{scene_.path, r.commands.line}, "robot '" + r.name + "' must drive commands of type test_drive for a PID test run, not " +
                                r.commands.type);
  drive_.start = r.commands.start;
  drive_.drive_time = r.commands.drive_time;
  drive_.direction = r.commands.direction_deg * kPi / 180;
  drive_.duration = scene_.duration;
  drive_.frame_rate = scene_.frame_rate;
  drive_.command_delay_frames = r.model.command_delay_frames;
  drive_.vision_delay_frames = r.model.vision_delay_frames;
  const double after_stop = scene_.duration - drive_.start - drive_.drive_time -
                            (drive_.command_delay_frames + drive_.vision_delay_frames) / scene_.frame_rate;
  if (after_stop < 0.5)
    throw InputError(where, "the scene ends " + std::to_string(after_stop) +
                                " s after the stop is seen; a PID test run needs at least 0.5 s to come to rest "
                                "(raise duration)");
}

std::vector<FrameRecord> TestRunEvaluator::Frames(const Eigen::VectorXd& parameters) const {
  Scene scene = scene_;
  scene.robots[0].model.controller = WithPidParameters(scene.robots[0].model.controller, parameters);
  Simulation sim = MakeSimulation(scene, backend_);
  return sim.Run(scene.num_frames()).frames[0];
}

TestRunScore TestRunEvaluator::Evaluate(const Eigen::VectorXd& parameters) const {
  try {
    return ScoreTestRun(Frames(parameters), drive_, weights_);
  } catch (const CheckFailed& e) {
    TestRunScore s;
    s.quality = kFailedQuality;
    s.failure = e.what();
    return s;
  }
}

std::vector<TestRunScore> TestRunEvaluator::EvaluateAll(const std::vector<Eigen::VectorXd>& sets, int threads) const {
  std::vector<TestRunScore> scores(sets.size());
  ParallelFor(static_cast<int>(sets.size()), threads, [&](int i) { scores[i] = Evaluate(sets[i]); });
  return scores;
}

bool PidTuningOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (start != "model" && start != "zeros") return fail("start must be 'model' or 'zeros'");
  if (!learn[0] && !learn[1] && !learn[2]) return fail("learn names no controller");
  if (iterations < 1) return fail("iterations must be at least 1");
  if (sets_per_iteration < 2) return fail("sets_per_iteration must be at least 2");
  if (!(exponent >= 1)) return fail("exponent must be >= 1");
  if (!(epsilon > 0) || !(eta >= 0)) return fail("epsilon must be > 0 and eta >= 0");
  if (scale.size() != 0 && (scale.size() != kPidParameters || !(scale.array() > 0).all()))
    return fail("scale needs 18 positive values");
  if (!(upper > 0)) return fail("upper must be > 0");
  if (threads < 0) return fail("threads must be >= 0");
  return true;
}

PidTuningOptions ReadPidTuningOptions(const Scene& scene) {
  PidTuningOptions o;
  o.seed = scene.seed;
  if (!scene.tune_pid.IsDefined() || scene.tune_pid.IsNull()) return o;
  ErrorList errors;
  YamlMap m(scene.tune_pid, scene.path, "tune_pid", &errors);
  m.Get("start", &o.start, {"model", "zeros"});
  if (m.Has("learn")) {
    const YAML::Node learn = m.Child("learn");
    static const std::vector<std::string> axes = {"forward", "sideways", "rotation"};
    if (!learn.IsSequence() || learn.size() == 0) {
      m.Error("learn", "expected a non-empty list of controllers (forward, sideways, rotation)");
    } else {
      o.learn = {false, false, false};
      for (const YAML::Node& item : learn) {
        const std::string name = item.IsScalar() ? item.as<std::string>() : "";
        const auto it = std::find(axes.begin(), axes.end(), name);
        if (it == axes.end())
          errors.Add(m.Where(item), "tune_pid.learn: unknown controller '" + name + "' (known: forward, sideways, rotation)");
        else
          o.learn[static_cast<std::size_t>(it - axes.begin())] = true;
      }
    }
  }
  m.Get("iterations", &o.iterations, InRange(1, 10000));
  m.Get("sets_per_iteration", &o.sets_per_iteration, InRange(2, 10000));
  m.Get("exponent", &o.exponent, InRange(1, 100));
  m.Get("patience", &o.patience, InRange(0, 10000));
  m.Get("epsilon", &o.epsilon, Positive());
  m.Get("eta", &o.eta, NonNegative());
  m.Get("upper", &o.upper, Positive());
  if (m.Has("weights")) {
    YamlMap w(m.Child("weights"), scene.path, "tune_pid.weights", &errors);
    w.Get("distance", &o.weights.distance, NonNegative());
    w.Get("deviation", &o.weights.deviation, NonNegative());
    w.Get("rotation", &o.weights.rotation, NonNegative());
    w.Get("stop_distance", &o.weights.stop_distance, NonNegative());
    w.Finish();
  }
  if (m.Has("scale")) {
    o.scale = DefaultPidScale();
    YamlMap sc(m.Child("scale"), scene.path, "tune_pid.scale", &errors);
    const char* axes[] = {"forward", "sideways", "rotation"};
    for (int a = 0; a < 3; ++a) {
      std::vector<double> v;
      if (sc.Get(axes[a], &v, 6, Positive())) o.scale.segment<6>(6 * a) = Eigen::Map<Eigen::VectorXd>(v.data(), 6);
    }
    sc.Finish();
  }
  m.Finish();
  errors.ThrowIfAny();
  return o;
}

PidTuningResult TunePid(const TestRunEvaluator& evaluator, const PidTuningOptions& options,
                        const std::function<void(const PidTuningIteration&)>& on_iteration) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("PID tuning options: " + why);
  const Eigen::VectorXd scale = options.scale.size() ? options.scale : DefaultPidScale();
  Eigen::VectorXd mask = Eigen::VectorXd::Zero(kPidParameters);
  for (int a = 0; a < 3; ++a)
    if (options.learn[a]) mask.segment<6>(6 * a).setOnes();

  PidTuningResult result;
  result.start_parameters = options.start == "zeros" ? Eigen::VectorXd::Zero(kPidParameters)
                                                     : PidParameters(evaluator.scene().robots[0].model.controller);
  PolicyGradientOptions pg;
  pg.sets_per_iteration = options.sets_per_iteration;
  pg.max_iterations = options.iterations;
  pg.epsilon = options.epsilon * scale.cwiseProduct(mask);
  pg.eta = options.eta * scale.cwiseProduct(mask);
  pg.lower = Eigen::VectorXd::Zero(kPidParameters);
  pg.upper = (options.upper * scale).cwiseMax(result.start_parameters);
  pg.exponent = options.exponent;
  pg.patience = options.patience;
  pg.seed = options.seed;

  std::vector<TestRunScore> last;  // the scores of the batch being evaluated
  auto evaluate = [&](const std::vector<Eigen::VectorXd>& sets) {
    last = evaluator.EvaluateAll(sets, options.threads);
    std::vector<double> q;
    for (const auto& s : last) q.push_back(s.quality);
    return q;
  };
  auto record = [&](const PolicyGradientIteration& it) {
    PidTuningIteration r;
    r.iteration = it.iteration;
    r.parameters = it.parameters;
    r.score = last.front();
    r.tested.assign(last.begin() + 1, last.end());
    result.iterations.push_back(r);
    if (on_iteration) on_iteration(result.iterations.back());
  };
  result.search = PolicyGradientSearch(result.start_parameters, pg, evaluate, record);
  result.best_parameters = result.search.best_parameters;
  result.best_score = result.iterations[result.search.best_iteration].score;
  result.test_runs = result.search.evaluations;
  return result;
}

}  // namespace twinsim
