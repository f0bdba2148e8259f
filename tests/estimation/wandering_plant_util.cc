#include "estimation/wandering_plant.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace twinsim::testing {
namespace {

// Standard normal draws from the engine's bits (Box-Muller), the same on every platform.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    const double u1 = (static_cast<double>(engine_() >> 11) + 0.5) / 9007199254740992.0;
    const double u2 = static_cast<double>(engine_() >> 11) / 9007199254740992.0;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }
  double Uniform() { return static_cast<double>(engine_() >> 11) / 9007199254740992.0; }

 private:
  std::mt19937_64 engine_;
};

}  // namespace

PlantRecording RecordWanderingPlant(const WanderingPlant& plant, double seconds, std::uint64_t seed) {
  Normal normal(seed);
  const int frames = static_cast<int>(std::lround(seconds * plant.frame_rate));
  const int substeps = 10;
  const double dt = 1.0 / plant.frame_rate / substeps;
  std::vector<std::array<double, 3>> sent(static_cast<std::size_t>(frames));
  std::array<double, 3> command{0, 0, 0};
  double hold = 0;
  for (int f = 0; f < frames; ++f) {
    if ((hold -= 1 / plant.frame_rate) <= 0) {
      hold = 0.3 + 0.9 * normal.Uniform();
      const bool stop = normal.Uniform() < 0.15;
      command = {stop ? 0 : plant.max_speed * (2 * normal.Uniform() - 1),
                 stop ? 0 : plant.max_speed * (2 * normal.Uniform() - 1),
                 stop ? 0 : plant.max_turn * (2 * normal.Uniform() - 1)};
    }
    sent[static_cast<std::size_t>(f)] = command;
  }
  PlantRecording out;
  std::vector<OmniLogRow> rows;
  double x = 0, y = 0, th = 0;
  std::array<double, 3> v{0, 0, 0}, d{0, 0, 0}, lagged{0, 0, 0};
  const double decay = std::exp(-dt / plant.noise_correlation);
  Pose2 smoothed;  // the camera's smoother, started on the first pose
  for (int f = 0; f < frames; ++f) {
    const double t = f / plant.frame_rate;
    out.truth.push_back(Pose2{x, y, th});
    out.velocity.push_back(Twist2{v[0] + d[0], v[1] + d[1], v[2] + d[2]});
    OmniLogRow row;
    row.t = t;
    const auto& c = sent[static_cast<std::size_t>(f)];
    row.command = Twist2{c[0], c[1], c[2]};
    const bool in_gap = plant.gap_start >= 0 && t >= plant.gap_start && t < plant.gap_start + plant.gap_seconds;
    row.measured = !in_gap && !(f > 1 && normal.Uniform() < plant.drop);
    row.pose = Pose2{x + plant.camera_xy * normal(), y + plant.camera_xy * normal(), th + plant.camera_theta * normal()};
    if (plant.camera_smoothing > 0) {
      const double k = f == 0 ? 1 : 1 - std::exp(-1 / (plant.frame_rate * plant.camera_smoothing));
      smoothed = Pose2{smoothed.x + k * (row.pose.x - smoothed.x), smoothed.y + k * (row.pose.y - smoothed.y),
                       smoothed.theta + k * (row.pose.theta - smoothed.theta)};
      row.pose = smoothed;
    }
    if (!row.measured) row.pose = rows.empty() ? Pose2{} : rows.back().pose;
    rows.push_back(row);
    // One frame of motion under the command sent delay_frames ago.
    const int from = f - plant.delay_frames;
    const std::array<double, 3> acting = from < 0 ? std::array<double, 3>{0, 0, 0} : sent[static_cast<std::size_t>(from)];
    for (int s = 0; s < substeps; ++s) {
      if (plant.field_frame_lag) {
        // The translation's lag state stays put in the field while the body turns.
        const double turn = -(v[2] + d[2]) * dt, cs = std::cos(turn), sn = std::sin(turn);
        const double vx = v[0];
        v[0] = cs * vx - sn * v[1];
        v[1] = sn * vx + cs * v[1];
      }
      std::array<double, 3> targets;
      for (int a = 0; a < 3; ++a) {
        // The hidden motor lag filters the command before the axes' own response.
        double& u = lagged[static_cast<std::size_t>(a)];
        u = plant.motor_lag > 0 ? u + (1 - std::exp(-dt / plant.motor_lag)) * (acting[static_cast<std::size_t>(a)] - u)
                                : acting[static_cast<std::size_t>(a)];
        targets[static_cast<std::size_t>(a)] = plant.gain[static_cast<std::size_t>(a)] * u * plant.speed_scale;
      }
      targets[2] += plant.turn_per_sideways * lagged[1] + plant.turn_per_forward * lagged[0];
      targets[1] += plant.sideways_per_forward * lagged[0];
      if (plant.turn_limit > 0) targets[2] = std::clamp(targets[2], -plant.turn_limit, plant.turn_limit);
      if (plant.max_translation > 0) {
        const double length = std::hypot(targets[0], targets[1]);
        if (length > plant.max_translation) targets[0] *= plant.max_translation / length, targets[1] *= plant.max_translation / length;
      }
      const std::array<double, 3> before = v;
      const double speed = std::min(1.0, std::hypot(v[0], v[1]) / plant.noise_full_speed);
      const double turn = std::min(1.0, std::abs(v[2]) / plant.noise_full_turn);
      const double f2 = plant.noise_still * plant.noise_still, g2 = plant.noise_not_turning * plant.noise_not_turning;
      const double grow = std::sqrt(f2 + (1 - f2) * speed * speed) * std::sqrt(g2 + (1 - g2) * turn * turn);
      for (int a = 0; a < 3; ++a) {
        const double target = targets[static_cast<std::size_t>(a)];
        double& va = v[static_cast<std::size_t>(a)];
        const double tau = plant.lag[static_cast<std::size_t>(a)] * ((target - va) * va < 0 ? plant.braking : 1);
        va += (1 - std::exp(-dt / tau)) * (target - va);
        d[static_cast<std::size_t>(a)] = decay * d[static_cast<std::size_t>(a)] +
                                         grow * plant.noise_sd[static_cast<std::size_t>(a)] * std::sqrt(1 - decay * decay) * normal();
      }
      if (plant.max_acceleration > 0) {
        // The wheels grip up to max_acceleration: the translation's change is cut to it.
        const double ax = (v[0] - before[0]) / dt, ay = (v[1] - before[1]) / dt, a = std::hypot(ax, ay);
        if (a > plant.max_acceleration) {
          v[0] = before[0] + ax * plant.max_acceleration / a * dt;
          v[1] = before[1] + ay * plant.max_acceleration / a * dt;
        }
      }
      const double bx = v[0] + d[0] + plant.run_drift[0], by = v[1] + d[1] + plant.run_drift[1],
                   w = v[2] + d[2] + plant.run_drift[2] + plant.turn_per_metre * std::hypot(bx, by);
      x += dt * (std::cos(th) * bx - std::sin(th) * by);
      y += dt * (std::sin(th) * bx + std::cos(th) * by);
      th += dt * w;
    }
  }
  out.log = ParseOmniLog(FormatOmniLog(rows), "wandering.csv");
  return out;
}

OmniModel ResemblingModel(OmniModel m, const WanderingPlant& plant) {
  m.command_delay_frames = plant.delay_frames / 2;
  m.vision_delay_frames = plant.delay_frames - m.command_delay_frames;
  for (std::size_t a = 0; a < 3; ++a) {
    m.effects.axis_scale[a] = plant.gain[a];
    m.effects.axis_lag[a] = plant.lag[a];
  }
  m.controller.forward.slew_rate = m.controller.sideways.slew_rate = 50;
  m.controller.rotation.slew_rate = 500;
  m.vision_noise_xy = plant.camera_xy;
  m.vision_noise_theta = plant.camera_theta;
  m.effects.lag_field_frame = plant.field_frame_lag;
  m.effects.lag_braking = plant.braking;
  m.effects.w_max = plant.turn_limit;
  m.effects.turn_per_sideways = plant.turn_per_sideways;
  m.driving_noise.sd = plant.noise_sd;
  m.driving_noise.correlation_time = plant.noise_correlation;
  return m;
}

double ConstantVelocityRmse(const OmniLog& log, int horizon, std::size_t first_row) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = first_row; i < log.rows.size(); ++i) {
    if (!log.rows[i].measured) continue;
    const int origin = log.FrameIndex(i) - horizon;
    // The last two measured rows at or before the origin frame.
    long b = -1, a = -1;
    for (long j = static_cast<long>(i) - 1; j >= 0; --j) {
      if (!log.rows[static_cast<std::size_t>(j)].measured || log.FrameIndex(static_cast<std::size_t>(j)) > origin) continue;
      if (b < 0) {
        b = j;
      } else {
        a = j;
        break;
      }
    }
    if (a < 0) continue;
    const OmniLogRow& rb = log.rows[static_cast<std::size_t>(b)];
    const OmniLogRow& ra = log.rows[static_cast<std::size_t>(a)];
    const double span = rb.t - ra.t, ahead = log.rows[i].t - rb.t;
    const double px = rb.pose.x + (rb.pose.x - ra.pose.x) / span * ahead;
    const double py = rb.pose.y + (rb.pose.y - ra.pose.y) / span * ahead;
    sum += std::pow(px - log.rows[i].pose.x, 2) + std::pow(py - log.rows[i].pose.y, 2);
    ++n;
  }
  return n ? std::sqrt(sum / n) : 0;
}

}  // namespace twinsim::testing
