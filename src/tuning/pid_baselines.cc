#include "tuning/pid_baselines.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "core/progress.h"

namespace twinsim {
namespace {

constexpr double kStepSize[3] = {0.5, 0.5, 2.0};  // m/s, m/s, rad/s: the step experiment's command

// The velocity of `axis` after a step command, with a P-only controller of gain kp on
// that axis, filmed at the controller's rate without delay (the robot's own encoders).
std::vector<double> StepExperiment(const TestRunEvaluator& evaluator, const Eigen::VectorXd& parameters, int axis,
                                   double kp) {
  Scene scene = evaluator.scene();
  SceneRobot& robot = scene.robots[0];
  Eigen::VectorXd p = parameters;
  Eigen::Matrix<double, 6, 1> g = p.segment<6>(6 * axis);
  g[0] = kp, g[1] = 0, g[2] = 0, g[3] = 0;
  g[5] = 1e3 * kStepSize[axis];  // a step, not a ramp
  p.segment<6>(6 * axis) = g;
  robot.model.controller = WithPidParameters(robot.model.controller, p);
  robot.model.command_delay_frames = robot.model.vision_delay_frames = 0;
  robot.model.vision_noise_xy = robot.model.vision_noise_theta = robot.model.vision_drop_probability = 0;
  scene.frame_rate = robot.model.controller.rate_hz;
  scene.physics_substeps = 0;
  scene.duration = 0.6;
  robot.commands = CommandSpec{};
  Twist2 step;
  (axis == 0 ? step.vx : axis == 1 ? step.vy : step.omega) = kStepSize[axis];
  robot.commands.segments = {{0.05, Twist2{}, false}, {1.0, step, false}};
  Simulation sim = MakeSimulation(scene, evaluator.backend());
  const SimulationResult result = sim.Run(scene.num_frames());
  std::vector<double> v;
  for (const FrameRecord& f : result.frames[0]) {
    const Twist2& t = f.truth_velocity;
    v.push_back(axis == 0 ? t.vx : axis == 1 ? t.vy : t.omega);
  }
  return v;
}

// True when the oscillation about the mean does not decay over the second half of the
// record; `period` (in samples) from its mean-crossings.
bool Sustained(const std::vector<double>& v, double step, double* period) {
  const std::size_t n = v.size(), a = n / 2, m = (n + a) / 2;
  double mean = 0;
  for (std::size_t i = a; i < n; ++i) mean += v[i];
  mean /= static_cast<double>(n - a);
  auto rms = [&](std::size_t from, std::size_t to) {
    double s = 0;
    for (std::size_t i = from; i < to; ++i) s += (v[i] - mean) * (v[i] - mean);
    return std::sqrt(s / static_cast<double>(to - from));
  };
  const double early = rms(a, m), late = rms(m, n);
  int crossings = 0;
  std::size_t first = 0, last = 0;
  for (std::size_t i = a + 1; i < n; ++i) {
    if ((v[i - 1] - mean) * (v[i] - mean) < 0) {
      if (!crossings) first = i;
      last = i;
      ++crossings;
    }
  }
  *period = crossings > 1 ? 2.0 * static_cast<double>(last - first) / (crossings - 1) : 0;
  return late > 1e-3 * step && late >= 0.8 * early && crossings >= 4;
}

}  // namespace

UltimateGain FindUltimateGain(const TestRunEvaluator& evaluator, const Eigen::VectorXd& parameters, int axis,
                              int max_experiments) {
  UltimateGain u;
  const double rate = evaluator.scene().robots[0].model.controller.rate_hz;
  double period = 0;
  auto oscillates = [&](double kp) {
    ++u.experiments;
    return Sustained(StepExperiment(evaluator, parameters, axis, kp), kStepSize[axis], &period);
  };
  // Bracket by doubling from the hand-tuned size, then bisect (geometrically).
  double lo = 0, hi = DefaultPidScale()[6 * axis];
  bool found = false;
  while (u.experiments < max_experiments && !(found = oscillates(hi))) lo = hi, hi *= 2;
  if (!found) return u;  // never oscillated within the budget: no ultimate gain
  double hi_period = period;
  while (u.experiments < max_experiments) {
    const double mid = lo > 0 ? std::sqrt(lo * hi) : hi / 2;
    if (oscillates(mid)) {
      hi = mid;
      hi_period = period;
    } else {
      lo = mid;
    }
    if (hi - lo < 0.01 * hi) break;
  }
  u.ku = hi;
  u.tu = hi_period / rate;
  return u;
}

BaselineResult ZieglerNicholsBaseline(const TestRunEvaluator& evaluator, const Eigen::VectorXd& start,
                                      const std::array<bool, 3>& learn, int budget) {
  BaselineResult r;
  r.method = "Ziegler-Nichols";
  // The limits and slew rates ZN does not set: the start set's, or the hand-tuned ones.
  Eigen::VectorXd p = start;
  const Eigen::VectorXd hand = PidParameters(OmniControllerModel{});
  const int axes = static_cast<int>(learn[0]) + learn[1] + learn[2];
  char text[160];
  for (int a = 0; a < 3; ++a) {
    if (!learn[a]) continue;
    for (int k : {3, 4, 5})
      if (p[6 * a + k] <= 0) p[6 * a + k] = hand[6 * a + k];
    const UltimateGain u = FindUltimateGain(evaluator, p, a, std::max(4, (budget - 1) / axes));
    r.test_runs += u.experiments;
    std::snprintf(text, sizeof text, "%sKu%d = %.4g, Tu%d = %.4g s", r.detail.empty() ? "" : ", ", a, u.ku, a, u.tu);
    r.detail += text;
    if (u.ku <= 0 || u.tu <= 0) continue;  // no oscillation found: keep the start set's gains
    p[6 * a + 0] = 0.6 * u.ku;
    p[6 * a + 1] = 1.2 * u.ku / u.tu;
    p[6 * a + 2] = 0.075 * u.ku * u.tu;
  }
  r.parameters = p;
  r.score = evaluator.Evaluate(p);
  ++r.test_runs;
  return r;
}

BaselineResult OptimizerBaseline(const TestRunEvaluator& evaluator, const Eigen::VectorXd& start,
                                 const PidTuningOptions& options, int budget) {
  const Eigen::VectorXd scale = options.scale.size() ? options.scale : DefaultPidScale();
  std::vector<int> free;
  for (int i = 0; i < kPidParameters; ++i)
    if (options.learn[static_cast<std::size_t>(i / 6)]) free.push_back(i);
  const int n = static_cast<int>(free.size());
  nlopt::srand(options.seed);
  nlopt::opt opt(nlopt::LN_SBPLX, static_cast<unsigned>(n));
  std::vector<double> x(n), lower(n, 0.0), upper(n), step(n);
  for (int k = 0; k < n; ++k) {
    const int i = free[static_cast<std::size_t>(k)];
    x[k] = start[i] / scale[i];
    upper[k] = std::max(options.upper, x[k]);
    step[k] = options.epsilon;
  }
  opt.set_lower_bounds(lower);
  opt.set_upper_bounds(upper);
  opt.set_initial_step(step);
  opt.set_maxeval(budget);

  BaselineResult r;
  r.method = "NLopt Subplex";
  r.parameters = start;
  r.score.quality = -INFINITY;
  auto to_parameters = [&](const std::vector<double>& xs) {
    Eigen::VectorXd p = start;
    for (int k = 0; k < n; ++k) p[free[static_cast<std::size_t>(k)]] = xs[k] * scale[free[static_cast<std::size_t>(k)]];
    return p;
  };
  std::function<double(const std::vector<double>&)> objective = [&](const std::vector<double>& xs) {
    const Eigen::VectorXd p = to_parameters(xs);
    const TestRunScore score = evaluator.Evaluate(p);
    ++r.test_runs;
    if (score.quality > r.score.quality) r.score = score, r.parameters = p;
    return score.quality;
  };
  opt.set_max_objective(
      [](const std::vector<double>& xs, std::vector<double>&, void* f) {
        return (*static_cast<std::function<double(const std::vector<double>&)>*>(f))(xs);
      },
      &objective);
  double value = 0;
  try {
    opt.optimize(x, value);
  } catch (const nlopt::roundoff_limited&) {
    // Stopped by round-off: the best point so far stands.
  }
  return r;
}

std::vector<BaselineResult> RunPidBaselines(const TestRunEvaluator& evaluator, const PidTuningResult& learned,
                                            const PidTuningOptions& options, bool quiet) {
  std::vector<BaselineResult> out;
  out.push_back(BaselineResult{"policy gradient", learned.test_runs, learned.best_parameters, learned.best_score, ""});
  const Eigen::VectorXd hand = PidParameters(evaluator.scene().robots[0].model.controller);
  out.push_back(BaselineResult{"hand-tuned (model)", 1, hand, evaluator.Evaluate(hand), ""});
  Progress progress("baselines", !quiet);
  progress.Update(0, 2, "Ziegler-Nichols");
  out.push_back(ZieglerNicholsBaseline(evaluator, learned.start_parameters, options.learn, learned.test_runs));
  progress.Update(1, 2, "NLopt Subplex");
  out.push_back(OptimizerBaseline(evaluator, learned.start_parameters, options, learned.test_runs));
  progress.Finish();
  return out;
}

}  // namespace twinsim
