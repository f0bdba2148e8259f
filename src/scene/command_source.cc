#include "scene/command_source.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {
namespace {

Twist2 Lerp(const Twist2& a, const Twist2& b, double s) {
  return Twist2{a.vx + s * (b.vx - a.vx), a.vy + s * (b.vy - a.vy), a.omega + s * (b.omega - a.omega)};
}

// A piecewise command: hold or ramp segments, zero after the last one.
class SegmentSource final : public CommandSource {
 public:
  SegmentSource(std::vector<CommandSpec::Segment> segments, int repeat)
      : segments_(std::move(segments)), repeat_(repeat) {
    for (const auto& s : segments_) period_ += s.duration;
  }
  Twist2 Command(const BehaviourInput& in) override {
    if (period_ <= 0) return Twist2{};
    double t = in.t;
    if (t >= period_ * repeat_) return Twist2{};
    t = std::fmod(t, period_);
    Twist2 previous{};
    for (const auto& s : segments_) {
      if (t < s.duration) return s.ramp ? Lerp(previous, s.command, t / s.duration) : s.command;
      t -= s.duration;
      previous = s.command;
    }
    return Twist2{};
  }
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<SegmentSource>(*this); }

 private:
  std::vector<CommandSpec::Segment> segments_;
  int repeat_ = 1;
  double period_ = 0;
};

// A lemniscate x = A sin(w t), y = A/2 sin(2 w t) driven open loop without turning:
// the field velocity is turned into the robot frame with the start heading.
class FigureEightSource final : public CommandSource {
 public:
  FigureEightSource(const CommandSpec& spec, const Pose2& start) : spec_(spec), heading_(start.theta) {}
  Twist2 Command(const BehaviourInput& in) override {
    const double t = in.t - spec_.start;
    if (t < 0 || t >= spec_.period * spec_.laps) return Twist2{};
    const double w = 2 * kPi / spec_.period, a = spec_.size;
    Twist2 field{a * w * std::cos(w * t), a * w * std::cos(2 * w * t), 0};
    return FieldToBody(field, heading_);
  }
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<FigureEightSource>(*this); }

 private:
  CommandSpec spec_;
  double heading_;
};

// Drives to each target in turn on the delayed observations: speed limited by the
// braking distance, heading by a proportional law, both capped.
class GoToPoseSource final : public CommandSource {
 public:
  explicit GoToPoseSource(const CommandSpec& spec) : spec_(spec) {}
  Twist2 Command(const BehaviourInput& in) override {
    Twist2 cmd = Decide(in);
    sent_.push_back(cmd);
    if (sent_.size() > 64) sent_.erase(sent_.begin());
    return cmd;
  }
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<GoToPoseSource>(*this); }

 private:
  // The pose to act on: the newest observation, or with a predictor, where the robot
  // will be D frames after it, from the last observations and the commands already sent.
  Pose2 Believed(const BehaviourInput& in) {
    const std::vector<Observation>& seen = *in.observations;
    if (!spec_.predictor) return seen.back().pose;
    const FeatureLayout& layout = spec_.predictor->info().layout;
    const int h = layout.history, lag = layout.command_lag;
    const int newest_row = in.frame;
    // Commands acting at row r were sent `lag` frames earlier; sent_ holds rows
    // newest_row - sent_.size() .. newest_row - 1. Before the run the robot stood still.
    bool known = true;
    auto acting = [&](int row) {
      const int frame = row - lag;
      const int back = newest_row - frame;  // 1 = the previous frame's command
      if (frame < 0) return Twist2{};
      if (back < 1 || back > static_cast<int>(sent_.size())) {
        known = false;
        return Twist2{};
      }
      return sent_[sent_.size() - static_cast<std::size_t>(back)];
    };
    if (layout.residual) Follow(seen, newest_row, acting);
    // The window: observations delivered in rows k - h + 1 .. k, k = now.
    if (static_cast<int>(seen.size()) < h || seen.back().delivered != in.frame) return seen.back().pose;
    std::vector<Pose2> poses(static_cast<std::size_t>(h));
    for (int j = 0; j < h; ++j) {
      const Observation& o = seen[seen.size() - static_cast<std::size_t>(h - j)];
      if (o.delivered != newest_row - (h - 1 - j)) return seen.back().pose;  // a lost frame
      poses[static_cast<std::size_t>(j)] = o.pose;
    }
    // Commands acting at rows k-h+1 .. k+H-1; the newest needed was sent at k+H-1-lag,
    // which is before now when H <= lag.
    std::vector<Twist2> commands(static_cast<std::size_t>(layout.num_commands()));
    for (int j = 0; j < layout.num_commands(); ++j) commands[static_cast<std::size_t>(j)] = acting(newest_row - h + 1 + j);
    if (!known) return seen.back().pose;
    if (!layout.residual) return spec_.predictor->Predict(poses.data(), commands.data());
    if (!track_ || newest_row - track_start_ < kNominalWarmUpFrames) return seen.back().pose;
    return spec_.predictor->Predict(poses.data(), commands.data(), &*track_);
  }

  // A residual predictor's Newtonian model, carried along the observations up to row
  // `newest_row` (as training carried it along the log): stepped a frame at a time under
  // the commands acting then, corrected to every observation. It starts at the first two
  // consecutive observations, with their velocity.
  template <typename Acting>
  void Follow(const std::vector<Observation>& seen, int newest_row, Acting& acting) {
    auto observed = [&](int row) -> const Observation* {
      for (auto it = seen.rbegin(); it != seen.rend() && it->delivered >= row; ++it)
        if (it->delivered == row) return &*it;
      return nullptr;
    };
    if (!track_) {
      const Observation* now = observed(newest_row);
      const Observation* before = observed(newest_row - 1);
      if (!now || !before) return;
      if (!spec_.predictor_model)
        throw std::logic_error("go_to_pose: a residual predictor needs CommandSpec::predictor_model (the robot's model)");
      track_.emplace(spec_.predictor->MakeNominalTrack(*spec_.predictor_model));
      track_->Reset(now->pose, BodyVelocityBetween(before->pose, now->pose, spec_.predictor->info().frame_rate));
      track_row_ = track_start_ = newest_row;
      return;
    }
    for (int row = track_row_ + 1; row <= newest_row; ++row) {
      track_->Step(acting(row - 1));
      if (const Observation* o = observed(row)) track_->Correct(o->pose);
    }
    track_row_ = std::max(track_row_, newest_row);
  }

  Twist2 Decide(const BehaviourInput& in) {
    if (!in.observations || in.observations->empty() || target_ >= spec_.targets.size()) return Twist2{};
    const Pose2 seen = Believed(in);
    const Pose2& goal = spec_.targets[target_];
    const double dx = goal.x - seen.x, dy = goal.y - seen.y;
    const double distance = std::hypot(dx, dy);
    const double dtheta = WrapAngle(goal.theta - seen.theta);

    if (distance < spec_.position_tolerance && std::abs(dtheta) < spec_.angle_tolerance) {
      if (!inside_since_) inside_since_ = in.t;
      if (in.t - *inside_since_ >= spec_.hold && target_ + 1 < spec_.targets.size()) {
        ++target_;
        inside_since_.reset();
      }
    } else {
      inside_since_.reset();
    }

    double speed = std::min({spec_.max_speed, std::sqrt(2 * spec_.max_accel * distance), spec_.gain * distance});
    Twist2 field{0, 0, std::clamp(spec_.gain * dtheta, -spec_.max_omega, spec_.max_omega)};
    if (distance > 1e-9) {
      field.vx = speed * dx / distance;
      field.vy = speed * dy / distance;
    }
    return FieldToBody(field, seen.theta);
  }

  CommandSpec spec_;
  std::optional<NominalOmniTrack> track_;  // a residual predictor's model, at row track_row_
  int track_row_ = 0, track_start_ = 0;
  std::size_t target_ = 0;
  std::optional<double> inside_since_;
  std::vector<Twist2> sent_;  // the commands sent so far (recent window), oldest first
};

// Keeps a drive near its start as seen through the delayed observations: outside the
// leash the translational command keeps its speed but points back to the start.
class LeashedSource final : public CommandSource {
 public:
  LeashedSource(std::unique_ptr<CommandSource> inner, const Pose2& start, double leash)
      : inner_(std::move(inner)), start_(start), leash_(leash) {}
  LeashedSource(const LeashedSource& other)
      : inner_(other.inner_->Clone()), start_(other.start_), leash_(other.leash_) {}
  Twist2 Command(const BehaviourInput& in) override {
    Twist2 cmd = inner_->Command(in);
    if (!in.observations || in.observations->empty()) return cmd;
    const Pose2& seen = in.observations->back().pose;
    const double dx = start_.x - seen.x, dy = start_.y - seen.y;
    const double distance = std::hypot(dx, dy);
    if (distance <= leash_) return cmd;
    const double speed = std::hypot(cmd.vx, cmd.vy);
    const Twist2 back = FieldToBody(Twist2{speed * dx / distance, speed * dy / distance, 0}, seen.theta);
    cmd.vx = back.vx;
    cmd.vy = back.vy;
    return cmd;
  }
  std::unique_ptr<CommandSource> Clone() const override { return std::make_unique<LeashedSource>(*this); }

 private:
  std::unique_ptr<CommandSource> inner_;
  Pose2 start_;
  double leash_;
};

std::vector<CommandSpec::Segment> RandomPlan(const CommandSpec& spec, std::uint64_t seed, int robot,
                                             double duration) {
  Rng rng = Rng::Derived(seed, 1000 + static_cast<std::uint64_t>(robot));
  std::vector<CommandSpec::Segment> plan;
  double t = 0;
  while (t < duration) {
    CommandSpec::Segment s;
    s.duration = rng.Uniform(spec.min_segment, spec.max_segment);
    if (rng.Uniform() >= spec.rest_probability) {
      const double direction = rng.Uniform(-kPi, kPi);
      const double speed = spec.max_speed * std::sqrt(rng.Uniform());  // fills the disc evenly
      s.command.vx = speed * std::cos(direction);
      s.command.vy = speed * std::sin(direction);
      if (rng.Uniform() < spec.rotate_probability) s.command.omega = rng.Uniform(-spec.max_omega, spec.max_omega);
      // Driving a curve at speed v and turn rate omega takes v * omega of sideways grip.
      if (spec.max_centripetal > 0 && speed * std::abs(s.command.omega) > spec.max_centripetal)
        s.command.omega = std::copysign(spec.max_centripetal / speed, s.command.omega);
    }
    s.ramp = rng.Uniform() < spec.ramp_probability;
    plan.push_back(s);
    t += s.duration;
  }
  return plan;
}

}  // namespace

std::unique_ptr<CommandSource> MakeCommandSource(const CommandSpec& spec, std::uint64_t seed,
                                                 int robot_index, double duration,
                                                 const Pose2& start) {
  if (spec.type == "sequence") return std::make_unique<SegmentSource>(spec.segments, spec.repeat);
  if (spec.type == "test_drive") {
    const double a = spec.direction_deg * kPi / 180.0;
    std::vector<CommandSpec::Segment> s = {
        {spec.start, Twist2{}, false},
        {spec.drive_time, Twist2{spec.speed * std::cos(a), spec.speed * std::sin(a), 0}, false}};
    return std::make_unique<SegmentSource>(s, 1);
  }
  if (spec.type == "figure_eight") return std::make_unique<FigureEightSource>(spec, start);
  if (spec.type == "random") {
    auto plan = std::make_unique<SegmentSource>(RandomPlan(spec, seed, robot_index, duration), 1);
    if (spec.leash <= 0) return plan;
    return std::make_unique<LeashedSource>(std::move(plan), start, spec.leash);
  }
  if (spec.type == "log") return std::make_unique<LogCommandSource>(spec.log);
  return std::make_unique<GoToPoseSource>(spec);
}

std::vector<CommandSpec> LogCommandSpecs(const std::string& path, const std::vector<std::string>& names,
                                         double frame_rate) {
  std::vector<CommandSpec> specs;
  for (const std::string& name : names) {
    CommandSpec spec;
    spec.type = "log";
    spec.log_path = path;
    spec.log_robot = name;
    spec.log = std::make_shared<CommandLog>(ReadCommandLog(path, name, frame_rate));
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace twinsim
