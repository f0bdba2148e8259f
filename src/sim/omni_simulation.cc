#include "sim/omni_simulation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <sstream>

#include "core/error.h"
#include "core/interrupt.h"
#include "robots/omni/omni_driving_noise.h"

namespace twinsim {

RobotCapture CaptureRobot(const Pose2& truth, const VisionNoise& noise, const OmniModel& model, Rng* rng,
                          std::optional<Pose2>* last) {
  RobotCapture out;
  out.pose = truth;
  out.pose.x += rng->Gaussian(noise.xy);
  out.pose.y += rng->Gaussian(noise.xy);
  out.pose.theta = WrapAngle(out.pose.theta + rng->Gaussian(noise.theta));
  out.lost = rng->Uniform() < model.vision_drop_probability;
  // A real camera now and then sends its last pose again.
  if (model.vision_repeat_probability > 0) {
    if (rng->Uniform() < model.vision_repeat_probability && *last) out.pose = **last;
    *last = out.pose;
  }
  return out;
}

double StampJitter(double vision_time_jitter, Rng* rng) {
  return vision_time_jitter > 0 ? vision_time_jitter * (2 * rng->Uniform() - 1) : 0.0;
}
namespace {

// A robot faster than this, or this far outside any field, has diverged.
constexpr double kMaxSpeed = 50;       // m/s
constexpr double kMaxOmega = 1000;     // rad/s
constexpr double kMaxDistance = 1000;  // m

// Where the ball's world keeps robot i while it is off the field: beyond kMaxDistance,
// so the ball diverges (and the run stops) before it could touch one.
Pose2 BallWorldParkedPose(int robot) { return Pose2{0, 1e4 + 10.0 * robot, 0}; }

}  // namespace

Pose2 Simulation::ParkedPose(int robot) { return Pose2{500 + 2.0 * robot, 500, 0}; }

Simulation::Simulation(std::vector<SimRobot> robots, std::unique_ptr<OmniBackend> backend,
                       std::uint64_t seed)
    : robots_(std::move(robots)), backend_(std::move(backend)) {
  state_.rng = Rng::Derived(seed, 0);
  state_.ball_rng = Rng::Derived(seed, 0x62616c6c);   // "ball"
  state_.drive_rng = Rng::Derived(seed, 0x64726976);  // "driv"
  for (int i = 0; i < num_robots(); ++i) {
    const SimRobot& r = robots_[static_cast<std::size_t>(i)];
    // A robot off the field at the start is parked, and the observer has seen nothing of it.
    const Pose2 start = r.present ? r.start : ParkedPose(i);
    backend_->Reset(i, start, Twist2{});
    state_.present.push_back(r.present);
    state_.slip.push_back({0, 0, 0});
    state_.drift.push_back({0, 0, 0});
    state_.drift_started.push_back(0);
    state_.pulls.emplace_back();
    state_.commands_in_flight.emplace_back(r.model.command_delay_frames, Twist2{});
    state_.captures_in_flight.emplace_back(r.model.vision_delay_frames,
                                           r.present ? std::optional<Pose2>(r.start) : std::nullopt);
    state_.delivered.emplace_back();
    state_.last_captured.emplace_back();
    state_.vision_noise.push_back(VisionNoise{r.model.vision_noise_xy, r.model.vision_noise_theta});
    FrameRecord first;
    first.truth = start;
    state_.last_good.push_back(first);
  }
}

void Simulation::CheckFinite(int robot, const Pose2& pose, const Twist2& v) {
  FrameRecord& good = state_.last_good[static_cast<std::size_t>(robot)];
  auto fail = [&](const std::string& what, double value) {
    std::ostringstream msg;
    msg << "simulation diverged at t = " << time() << " s (frame " << state_.frame << "), robot '"
        << robots_[static_cast<std::size_t>(robot)].name << "' on backend " << backend_->robot_backend(robot) << ": "
        << what << " = " << value << "; last good state at t = " << good.t << " s: x = " << good.truth.x
        << " m, y = " << good.truth.y << " m, theta = " << good.truth.theta << " rad, vx = "
        << good.truth_velocity.vx << " m/s, vy = " << good.truth_velocity.vy << " m/s, omega = "
        << good.truth_velocity.omega << " rad/s (robot frame)";
    throw CheckFailed(msg.str());
  };
  if (!std::isfinite(pose.x)) fail("x", pose.x);
  if (!std::isfinite(pose.y)) fail("y", pose.y);
  if (!std::isfinite(pose.theta)) fail("theta", pose.theta);
  if (!std::isfinite(v.vx) || std::abs(v.vx) > kMaxSpeed) fail("vx", v.vx);
  if (!std::isfinite(v.vy) || std::abs(v.vy) > kMaxSpeed) fail("vy", v.vy);
  if (!std::isfinite(v.omega) || std::abs(v.omega) > kMaxOmega) fail("omega", v.omega);
  if (std::hypot(pose.x, pose.y) > kMaxDistance) fail("distance from the field centre", std::hypot(pose.x, pose.y));
  good.t = time();
  good.truth = pose;
  good.truth_velocity = v;
}

std::vector<FrameRecord> Simulation::Step() {
  ThrowIfInterrupted();
  std::vector<FrameRecord> records = BeginFrame();
  std::vector<BallCommand> ball_commands(robots_.size());
  for (int i = 0; i < num_robots(); ++i) {
    if (!present(i)) continue;
    const auto k = static_cast<std::size_t>(i);
    records[k].command = SourceCommand(i);
    if (ball_) ball_commands[k] = SourceBallCommand(i);
  }
  EndFrame(&records, ball_commands);
  return records;
}

BallCommand Simulation::SourceBallCommand(int robot) {
  CommandSource* source = nullptr;
  const BehaviourInput in = SourceInput(robot, "SourceBallCommand", &source);
  return source ? source->Ball(in) : BallCommand{};
}

BehaviourInput Simulation::SourceInput(int robot, const char* caller, CommandSource** source) {
  if (!frame_open_) throw std::logic_error(std::string("Simulation::") + caller + ": no frame is open");
  const auto k = static_cast<std::size_t>(robot);
  *source = robots_.at(k).commands.get();
  BehaviourInput in;
  in.frame = state_.frame;
  in.t = time();
  in.observations = &state_.delivered[k];
  return in;
}

Twist2 Simulation::SourceCommand(int robot) {
  CommandSource* source = nullptr;
  const BehaviourInput in = SourceInput(robot, "SourceCommand", &source);
  return source ? source->Command(in) : Twist2{};
}

void Simulation::AddBall(std::unique_ptr<BallField> ball, const BallState& start, const BallVision& vision) {
  if (state_.frame != 0 || frame_open_) throw std::logic_error("Simulation::AddBall: after the first frame");
  if (!ball || ball->num_robots() != num_robots())
    throw std::invalid_argument("Simulation::AddBall: a ball field of another number of robots");
  ball_ = std::move(ball);
  state_.ball_vision = vision;
  ball_->Reset(start);
  state_.ball_commands_in_flight.clear();
  for (const SimRobot& r : robots_) state_.ball_commands_in_flight.emplace_back(r.model.command_delay_frames, BallCommand{});
  const int delay = robots_.empty() ? 0 : robots_.front().model.vision_delay_frames;
  state_.ball_captures_in_flight.emplace(delay, std::optional<Eigen::Vector3d>(start.position));
  state_.ball = ball_->Save();
  state_.ball_record = BallRecord{};
  state_.ball_record.truth = ball_->ball();
}

const BallRecord& Simulation::ball_record() const {
  if (!ball_) throw std::logic_error("Simulation::ball_record: no ball");
  return state_.ball_record;
}

void Simulation::TeleportBall(const BallState& state) {
  if (!ball_) throw std::logic_error("Simulation::TeleportBall: no ball");
  ball_->Reset(state);
  state_.ball_record.truth = ball_->ball();
}

void Simulation::PullBall(const Eigen::Vector2d& target) {
  if (!ball_) throw std::logic_error("Simulation::PullBall: no ball");
  ball_->Pull(target);
}

std::vector<FrameRecord> Simulation::BeginFrame() {
  if (frame_open_) throw std::logic_error("Simulation::BeginFrame: the previous frame was not ended");
  const double t = time();
  if (ball_) {
    // The camera sees the ball with its own noise stream (the robots' streams stay as
    // they are), drawn only when the scene asks for noise or lost frames.
    BallRecord& b = state_.ball_record;
    b = BallRecord{};
    b.t = t;
    b.truth = ball_->ball();
    if (!b.truth.position.allFinite() || !b.truth.velocity.allFinite() || b.truth.velocity.norm() > kMaxSpeed ||
        b.truth.position.norm() > kMaxDistance) {
      std::ostringstream msg;
      msg << "simulation diverged at t = " << t << " s (frame " << state_.frame << "): the ball is at ("
          << b.truth.position.transpose() << ") m moving at (" << b.truth.velocity.transpose() << ") m/s";
      throw CheckFailed(msg.str());
    }
    std::optional<Eigen::Vector3d> captured = b.truth.position;
    if (state_.ball_vision.any()) {
      *captured += Eigen::Vector3d(state_.ball_rng.Gaussian(state_.ball_vision.noise_xy),
                                   state_.ball_rng.Gaussian(state_.ball_vision.noise_xy),
                                   state_.ball_rng.Gaussian(state_.ball_vision.noise_z));
      if (state_.ball_rng.Uniform() < state_.ball_vision.drop_probability) captured.reset();
    }
    const std::optional<Eigen::Vector3d> arrived = state_.ball_captures_in_flight->Push(captured);
    b.observed = arrived.has_value();
    if (arrived) b.seen = *arrived;
  }
  std::vector<FrameRecord> records(robots_.size());
  for (int i = 0; i < num_robots(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    FrameRecord& rec = records[k];
    rec.t = t;
    rec.truth = backend_->pose(i);
    rec.truth_velocity = backend_->velocity(i);
    rec.present = state_.present[k];
    CheckFinite(i, rec.truth, rec.truth_velocity);

    // The camera: noise always drawn, so that dropping frames does not shift the stream.
    const OmniModel& m = robots_[k].model;
    const RobotCapture shot = CaptureRobot(rec.truth, state_.vision_noise[k], m, &state_.rng, &state_.last_captured[k]);
    rec.stamp = t + StampJitter(m.vision_time_jitter, &state_.rng);
    // A robot off the field is not captured (the draws above are made all the same, so
    // that the other robots' noise does not depend on it), and has nothing to repeat.
    if (!rec.present) state_.last_captured[k].reset();
    std::optional<Pose2> arrived =
        state_.captures_in_flight[k].Push(shot.lost || !rec.present ? std::nullopt : std::optional(shot.pose));

    auto& delivered = state_.delivered[k];
    if (arrived) {
      const int captured_frame = state_.frame - m.vision_delay_frames;
      delivered.push_back(
          Observation{captured_frame, state_.frame, captured_frame * backend_->timing().frame_dt(), *arrived});
      if (static_cast<int>(delivered.size()) > kObservationWindow) delivered.erase(delivered.begin());
      rec.observed = true;
      rec.seen = *arrived;
    }
  }
  frame_open_ = true;
  return records;
}

void Simulation::EndFrame(std::vector<FrameRecord>* records) {
  EndFrame(records, std::vector<BallCommand>(robots_.size()));
}

void Simulation::EndFrame(std::vector<FrameRecord>* records, const std::vector<BallCommand>& ball_commands) {
  if (!frame_open_) throw std::logic_error("Simulation::EndFrame: no frame was begun");
  if (ball_commands.size() != robots_.size())
    throw std::invalid_argument("Simulation::EndFrame: one ball command per robot");
  if (records->size() != robots_.size()) throw std::invalid_argument("Simulation::EndFrame: one record per robot");
  std::vector<Twist2> applied(robots_.size());
  for (std::size_t k = 0; k < robots_.size(); ++k) {
    // A robot off the field is sent nothing (what its sender gave is logged as zero).
    if (!state_.present[k]) {
      (*records)[k].command = Twist2{};
      (*records)[k].ball_command = BallCommand{};
    } else {
      (*records)[k].ball_command = ball_commands[k];
    }
    const Twist2& command = (*records)[k].command;
    if (!IsFinite(command)) {
      std::ostringstream msg;
      msg << "behaviour of robot '" << robots_[k].name << "' sent a non-finite command at t = " << (*records)[k].t
          << " s";
      throw CheckFailed(msg.str());
    }
    applied[k] = state_.commands_in_flight[k].Push(command);
    if (!state_.present[k]) applied[k] = Twist2{};
    // A move by force overrides what comes out of the delay line while it lasts.
    if (state_.pulls[k]) {
      if (std::optional<Twist2> pulled = PullCommand(static_cast<int>(k))) applied[k] = *pulled;
    }
  }
  frame_open_ = false;
  // The robots go first, then the ball through the same frame among them (one-way);
  // in the ball's world a robot off the field stands far beyond its reach.
  auto ball_world_pose = [&](int i) { return present(i) ? backend_->pose(i) : BallWorldParkedPose(i); };
  std::vector<Pose2> before;
  if (ball_) {
    for (int i = 0; i < num_robots(); ++i) before.push_back(ball_world_pose(i));
  }
  std::vector<Twist2> velocity_before;  // the wheels' own, for the driving noise's spread
  for (int i = 0; i < num_robots(); ++i) velocity_before.push_back(backend_->velocity(i));
  backend_->StepFrame(applied);
  // Parked robots are put back exactly where they were, at rest.
  for (int i = 0; i < num_robots(); ++i)
    if (!present(i)) backend_->Reset(i, ParkedPose(i), Twist2{});
  Slip(velocity_before);
  if (ball_) {
    std::vector<Pose2> after;
    std::vector<BallCommand> acting(robots_.size());
    for (int i = 0; i < num_robots(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      after.push_back(ball_world_pose(i));
      // What a robot sent before it left is still in flight: it does not act off the field.
      acting[k] = state_.ball_commands_in_flight[k].Push((*records)[k].ball_command);
      if (!present(i)) acting[k] = BallCommand{};
    }
    ball_->StepFrame(before, after, acting, backend_->timing().frame_dt());
  }
  ++state_.frame;
}

void Simulation::SetDrivingNoiseSample(std::uint64_t seed, std::uint64_t sample) {
  state_.drive_rng = Rng::Derived(seed, 0x64726976 + (sample << 32));  // "driv", sample 0 the constructor's
}

void Simulation::DrawModelParameters(std::uint64_t seed, std::uint64_t sample) {
  Rng rng = Rng::Derived(seed, 0x70617261 + (sample << 32));  // "para"
  backend_->DrawParameters(&rng);
}

void Simulation::Slip(const std::vector<Twist2>& velocity_before) {
  const double dt = backend_->timing().frame_dt();
  for (int i = 0; i < num_robots(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const OmniDrivingNoise& noise = robots_[k].model.driving_noise;
    if (!noise.simulated || !present(i) || state_.pulls[k]) continue;
    // The slip (robot frame) at the speed and acceleration of the robot's own (wheel)
    // velocity; the body moves on by it, the wheels unaware.
    if (!state_.drift_started[k]) {
      state_.drift[k] = StartDrift(noise, &state_.drive_rng);
      state_.drift_started[k] = 1;
    }
    backend_->PushBody(i, SlipPose(noise, dt, backend_->velocity(i), velocity_before[k], backend_->pose(i), &state_.slip[k],
                                   &state_.drive_rng, &state_.drift[k]));
  }
}

std::optional<Twist2> Simulation::PullCommand(int robot) {
  std::optional<RobotPull>& pull = state_.pulls.at(static_cast<std::size_t>(robot));
  const Pose2 pose = backend_->pose(robot);
  const Eigen::Vector2d error(pull->target.x - pose.x, pull->target.y - pose.y);
  const double turn = WrapAngle(pull->target.theta - pose.theta);
  const double distance = error.norm();
  if ((distance < kPullTolerance && std::abs(turn) < kPullAngleTolerance) || pull->frames_left <= 0) {
    pull.reset();
    return std::nullopt;
  }
  --pull->frames_left;
  // First order towards the target (time constant kPullTau), no faster than kPullSpeed
  // and slow enough to brake at kPullAccel before it; the robot's own controller and
  // motors then track the velocity, so its path stays continuous and its speed bounded.
  const double speed = std::min({kPullSpeed, distance / kPullTau, std::sqrt(2 * kPullAccel * distance)});
  const Eigen::Vector2d v = distance > 0 ? Eigen::Vector2d(error / distance * speed) : Eigen::Vector2d::Zero();
  const double omega = std::clamp(turn / kPullTau, -kPullOmega, kPullOmega);
  return FieldToBody(Twist2{v.x(), v.y(), omega}, pose.theta);
}

void Simulation::Teleport(int robot, const Pose2& pose, const Twist2& velocity) {
  if (!present(robot)) {
    throw std::logic_error("Simulation::Teleport: robot '" + robot_name(robot) + "' is off the field; Add() it");
  }
  state_.pulls[static_cast<std::size_t>(robot)].reset();
  backend_->Reset(robot, pose, velocity);
}

void Simulation::SetVisionNoise(int robot, double xy, double theta) {
  if (!(std::isfinite(xy) && xy >= 0 && std::isfinite(theta) && theta >= 0))
    throw std::invalid_argument("Simulation::SetVisionNoise: the noise must be finite and >= 0");
  state_.vision_noise.at(static_cast<std::size_t>(robot)) = VisionNoise{xy, theta};
}

void Simulation::SetBallVision(const BallVision& vision) {
  if (!ball_) throw std::logic_error("Simulation::SetBallVision: no ball");
  auto ok = [](double v) { return std::isfinite(v) && v >= 0; };
  if (!ok(vision.noise_xy) || !ok(vision.noise_z) || !ok(vision.drop_probability) || vision.drop_probability > 1)
    throw std::invalid_argument("Simulation::SetBallVision: the noise must be finite and >= 0, the probability in 0..1");
  state_.ball_vision = vision;
}

void Simulation::Remove(int robot) {
  const auto k = static_cast<std::size_t>(robot);
  if (!state_.present.at(k)) return;
  state_.present[k] = false;
  state_.pulls[k].reset();
  state_.last_captured[k].reset();
  backend_->Reset(robot, ParkedPose(robot), Twist2{});
}

void Simulation::Add(int robot, const Pose2& pose, const Twist2& velocity) {
  const auto k = static_cast<std::size_t>(robot);
  state_.present.at(k) = true;
  state_.pulls[k].reset();
  backend_->Reset(robot, pose, velocity);
}

void Simulation::PullRobot(int robot, const Pose2& target) {
  if (!present(robot)) {
    throw std::logic_error("Simulation::PullRobot: robot '" + robot_name(robot) + "' is off the field");
  }
  const int frames = static_cast<int>(std::ceil(kPullTimeout * backend_->timing().frame_rate));
  state_.pulls[static_cast<std::size_t>(robot)] = RobotPull{target, frames};
}

SimulationResult Simulation::Run(int frames, const std::function<void(int, int)>& progress) {
  SimulationResult result;
  result.backend = backend_->name();
  result.timing = backend_->timing();
  for (const auto& r : robots_) result.robot_names.push_back(r.name);
  for (int i = 0; i < num_robots(); ++i) result.robot_backends.push_back(backend_->robot_backend(i));
  result.frames.resize(robots_.size());
  for (auto& f : result.frames) f.reserve(static_cast<std::size_t>(frames));
  for (int k = 0; k < frames; ++k) {
    std::vector<FrameRecord> records = Step();
    for (std::size_t i = 0; i < records.size(); ++i) result.frames[i].push_back(records[i]);
    if (ball_) result.ball.push_back(state_.ball_record);
    if (progress && (k % 16 == 0 || k + 1 == frames)) progress(k + 1, frames);
  }
  result.grip = backend_->grip();
  return result;
}

SimulationState Simulation::Save() const {
  SimulationState s = state_;
  s.backend = backend_->Save();
  if (ball_) s.ball = ball_->Save();
  // A behaviour's copy is its state (a go-to-pose source's target and sent commands).
  for (const SimRobot& r : robots_) {
    s.behaviours.push_back(r.commands ? std::shared_ptr<const CommandSource>(r.commands->Clone()) : nullptr);
  }
  return s;
}

void Simulation::Restore(const SimulationState& state) {
  if (state.behaviours.size() != robots_.size() || state.commands_in_flight.size() != robots_.size() ||
      state.last_good.size() != robots_.size() || state.present.size() != robots_.size() ||
      state.pulls.size() != robots_.size() || state.vision_noise.size() != robots_.size()) {
    throw std::invalid_argument("Simulation::Restore: state of a simulation with another number of robots");
  }
  if (state.ball.has_value() != has_ball())
    throw std::invalid_argument("Simulation::Restore: state of a simulation with(out) a ball");
  backend_->Restore(state.backend);
  if (ball_) ball_->Restore(*state.ball);
  state_ = state;
  frame_open_ = false;
  state_.behaviours.clear();
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    robots_[i].commands = state.behaviours[i] ? state.behaviours[i]->Clone() : nullptr;
  }
}

}  // namespace twinsim
