#include "backends/engine_drives.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "backends/omni_backend_factory.h"

namespace twinsim::testing {

OmniModel Quiet(OmniModel m) {
  m.command_delay_frames = 0;
  m.vision_delay_frames = 0;
  m.vision_noise_xy = 0;
  m.vision_noise_theta = 0;
  return m;
}

CommandSpec TestDrive45() {
  CommandSpec spec;
  spec.type = "test_drive";
  spec.start = 0.2;
  spec.speed = 1.5;
  spec.direction_deg = 45;
  spec.drive_time = 1.5;
  return spec;
}

SimulationResult Drive(const std::string& backend, const OmniModel& model, const CommandSpec& spec, double seconds,
                       std::uint64_t seed, double frame_rate) {
  FrameTiming timing;
  timing.frame_rate = frame_rate;
  timing.physics_substeps = DefaultPhysicsSubsteps(frame_rate);
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", model, Pose2{0, 0, 0}, MakeCommandSource(spec, seed, 0, seconds, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend(backend, {model}, FieldModel{}, timing), seed);
  return sim.Run(static_cast<int>(std::lround(seconds * frame_rate)) + 1);
}

std::pair<double, double> LargestTruthDifference(const SimulationResult& a, const SimulationResult& b) {
  double position = 0, heading = 0;
  for (std::size_t k = 0; k < a.frames[0].size() && k < b.frames[0].size(); ++k) {
    const Pose2& p = a.frames[0][k].truth;
    const Pose2& q = b.frames[0][k].truth;
    position = std::max(position, std::hypot(p.x - q.x, p.y - q.y));
    heading = std::max(heading, std::abs(WrapAngle(p.theta - q.theta)));
  }
  return {position, heading};
}

}  // namespace twinsim::testing
