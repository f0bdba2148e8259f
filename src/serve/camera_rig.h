// The cameras of a served field (the scene's `cameras:`, scene/camera_layout.h;
// docs/serve.md "Several cameras"): each sees the true state of `vision_delay` frames
// ago in its area, with its own noise and lost detections from its own random stream,
// captured at its own instant (a staggered camera: up to a frame period earlier, the
// state interpolated between the two frames around it) and numbered by its own clock.
// Each draws its poses as `run`'s camera does (CaptureRobot: noise, lost detections,
// repeated poses) and stamps its frames with the models' time jitter.
// The cameras' draws never touch the simulation's streams, so the observer's logs are
// the same with cameras or without.
//
//   CameraRig rig(scene, sim, vision_delay);
//   per frame k: rig.Record(k, sim.BeginFrame(), sim); ...; rig.Packets(k, frame_time, t_sent, sim, roster);
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "core/rng.h"
#include "scene/camera_layout.h"
#include "scene/scene.h"
#include "serve/team_roster.h"
#include "sim/omni_simulation.h"
#include "ssl_vision_wrapper.pb.h"

namespace twinsim {

// What a camera that captures a share `a` (0..1) of a frame of `dt` s early sees: the
// true pose between frame j's (`now`, a = 0) and frame j - 1's (`before`, a = 1), the
// heading the short way round. A step faster than 25 m/s or 110 rad/s (a teleport, or a
// robot taken off or put on the field) is not interpolated across: `now`.
Pose2 CapturedPose(const Pose2& now, const Pose2& before, double a, double dt);
// The ball's, a step faster than 45 m/s not interpolated across.
Eigen::Vector3d CapturedBall(const Eigen::Vector3d& now, const Eigen::Vector3d& before, double a, double dt);

class CameraRig {
 public:
  CameraRig() = default;  // no cameras: the field sends what the observer receives
  // The scene's cameras over `sim` (the scene's simulation, before its first frame),
  // whose robots share a vision delay of `vision_delay` frames.
  CameraRig(const Scene& scene, const Simulation& sim, int vision_delay);

  bool empty() const { return views_.empty(); }
  const std::vector<CameraView>& views() const { return views_; }

  // Keeps the true state of frame `frame` (`records`: the frame as begun).
  void Record(int frame, const std::vector<FrameRecord>& records, const Simulation& sim);
  // Each camera's detection sent at frame k, one packet per camera in id order.
  // `frame_time(j)`: the time frame j began (s; j may be negative: before frame 0, frames
  // stamped as if they had run), the capture times' clock; `t_sent` the send time.
  std::vector<SSL_WrapperPacket> Packets(int k, const std::function<double(int)>& frame_time, double t_sent,
                                         const Simulation& sim, const TeamRoster& roster);

 private:
  struct Capture {
    std::vector<Pose2> robots;  // field frame, true
    std::vector<bool> present;
    Eigen::Vector3d ball = Eigen::Vector3d::Zero();  // m, true
  };
  const Capture& CaptureOf(int frame) const;

  std::vector<CameraView> views_;
  std::vector<Rng> rng_;           // per camera
  std::vector<std::vector<std::optional<Pose2>>> last_;  // per camera and robot: what it repeats
  double time_jitter_ = 0;         // s, the robots' largest vision_time_jitter
  std::vector<Capture> captures_;  // frame j's at j % (vision_delay + 2)
  Capture start_;                  // before frame 0: the robots at their starts
  int vision_delay_ = 0;
  double frame_dt_ = 0;  // s
};

}  // namespace twinsim
