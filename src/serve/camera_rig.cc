#include "serve/camera_rig.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "core/pose.h"
#include "serve/vision_packets.h"

namespace twinsim {
namespace {

// The cameras' random streams (noise and lost detections), one per camera id from this
// base, derived from the scene's seed: never the simulation's own streams.
constexpr std::uint64_t kCameraStream = 0x63616d00;  // "cam"
// A step faster than these between two frames is a teleport (a robot taken off or put
// on the field is parked far away), which a staggered camera's capture does not
// interpolate across: it sees the frame's pose. Robots are commanded at 20 m/s and
// 100 rad/s at most; a ball is kicked at 20 m/s at most, from a robot that may drive.
constexpr double kTeleportSpeed = 25;      // m/s, a robot
constexpr double kTeleportTurn = 110;      // rad/s
constexpr double kTeleportBallSpeed = 45;  // m/s

}  // namespace

Pose2 CapturedPose(const Pose2& now, const Pose2& before, double a, double dt) {
  const double turn = WrapAngle(before.theta - now.theta);
  if (std::hypot(now.x - before.x, now.y - before.y) > kTeleportSpeed * dt || std::abs(turn) > kTeleportTurn * dt)
    return now;
  return Pose2{now.x + a * (before.x - now.x), now.y + a * (before.y - now.y), WrapAngle(now.theta + a * turn)};
}

Eigen::Vector3d CapturedBall(const Eigen::Vector3d& now, const Eigen::Vector3d& before, double a, double dt) {
  if ((now - before).norm() > kTeleportBallSpeed * dt) return now;
  return now + a * (before - now);
}

CameraRig::CameraRig(const Scene& scene, const Simulation& sim, int vision_delay)
    : vision_delay_(vision_delay), frame_dt_(1 / scene.frame_rate) {
  if (!scene.cameras) return;
  views_ = CameraViews(*scene.cameras, scene.field, scene.frame_rate, scene.seed);
  for (const CameraView& v : views_) rng_.push_back(Rng::Derived(scene.seed, kCameraStream + v.id));
  last_.assign(views_.size(), std::vector<std::optional<Pose2>>(static_cast<std::size_t>(sim.num_robots())));
  start_.present.resize(static_cast<std::size_t>(sim.num_robots()));
  for (int i = 0; i < sim.num_robots(); ++i) {
    time_jitter_ = std::max(time_jitter_, sim.robot_model(i).vision_time_jitter);
    start_.robots.push_back(sim.backend().pose(i));
    start_.present[static_cast<std::size_t>(i)] = sim.present(i);
  }
  if (sim.has_ball()) start_.ball = sim.ball()->ball().position;
  captures_.assign(static_cast<std::size_t>(vision_delay) + 2, start_);
}

void CameraRig::Record(int frame, const std::vector<FrameRecord>& records, const Simulation& sim) {
  if (empty()) return;
  Capture& c = captures_[static_cast<std::size_t>(frame) % captures_.size()];
  for (std::size_t i = 0; i < records.size(); ++i) {
    c.robots[i] = records[i].truth;
    c.present[i] = records[i].present;
  }
  if (sim.has_ball()) c.ball = sim.ball()->ball().position;
}

const CameraRig::Capture& CameraRig::CaptureOf(int frame) const {
  // Before frame 0 the robots stood at their starts, as the observer has seen them.
  return frame >= 0 ? captures_[static_cast<std::size_t>(frame) % captures_.size()] : start_;
}

std::vector<SSL_WrapperPacket> CameraRig::Packets(int k, const std::function<double(int)>& frame_time, double t_sent,
                                                  const Simulation& sim, const TeamRoster& roster) {
  const int captured = k - vision_delay_;
  const Capture& now = CaptureOf(captured);
  const Capture& before = CaptureOf(captured - 1);
  std::vector<SSL_WrapperPacket> packets;
  for (std::size_t v = 0; v < views_.size(); ++v) {
    const CameraView& view = views_[v];
    Rng& rng = rng_[v];
    const double a = view.capture_lead / frame_dt_;  // 0: at the frame
    double t_capture = frame_time(captured);
    if (a > 0) t_capture = (1 - a) * t_capture + a * frame_time(captured - 1);
    // Every draw made whether or not the camera sees the object, so that what one
    // camera sees never shifts another's noise.
    std::vector<Sighting> seen;
    for (int i = 0; i < sim.num_robots(); ++i) {
      const auto ku = static_cast<std::size_t>(i);
      const Pose2 truth = a > 0 ? CapturedPose(now.robots[ku], before.robots[ku], a, frame_dt_) : now.robots[ku];
      // The camera `run` records (sim/omni_simulation.h), this camera's own stream.
      std::optional<Pose2>& last = last_[v][ku];
      const RobotCapture shot = CaptureRobot(truth, sim.vision_noise(i), sim.robot_model(i), &rng, &last);
      if (!now.present[ku]) last.reset();  // off the field: nothing to repeat
      if (now.present[ku] && !shot.lost && view.Sees(truth.x, truth.y))
        seen.push_back(Sighting{roster.robot(i), shot.pose});
    }
    std::optional<Eigen::Vector3d> ball;
    if (sim.has_ball()) {
      const BallVision& b = sim.ball_vision();
      const Eigen::Vector3d truth = a > 0 ? CapturedBall(now.ball, before.ball, a, frame_dt_) : now.ball;
      const Eigen::Vector3d p =
          truth + Eigen::Vector3d(rng.Gaussian(b.noise_xy), rng.Gaussian(b.noise_xy), rng.Gaussian(b.noise_z));
      const bool lost = rng.Uniform() < b.drop_probability;
      if (!lost && view.Sees(truth.x(), truth.y())) ball = p;
    }
    // The camera's frame stamped off its clock as `run`'s are (the robots' largest
    // vision.time_jitter; a draw only where there is one).
    t_capture += StampJitter(time_jitter_, &rng);
    packets.push_back(
        DetectionPacket(seen, view.first_frame + static_cast<std::uint32_t>(k), t_capture, t_sent, ball, &view));
  }
  return packets;
}

}  // namespace twinsim
