// Several cameras (scene `cameras:`, scene/camera_layout.h, docs/serve.md "Several
// cameras"): a grid of overlapping views, each camera sending its own detection frames
// with its own noise; objects in an overlap seen by each camera that sees them; the
// observer's logs as without cameras.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <thread>

#include "backends/omni_backend_factory.h"
#include "scene/camera_layout.h"
#include "scene/scene.h"
#include "serve/live_field.h"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

TEST(CameraLayout, AGridCoversTheFieldWithOverlapsBetweenNeighbours) {
  FieldModel field;
  field.length = 6;
  field.width = 4;
  const std::vector<CameraView> views = CameraViews(CameraGrid{2, 2, 0.4, 4}, field);
  ASSERT_EQ(views.size(), 4u);
  // Ids along x, then y; each above its cell's centre.
  EXPECT_EQ(views[1].id, 1);
  EXPECT_EQ(views[1].position, Eigen::Vector3d(1.5, -1, 4));
  EXPECT_EQ(views[2].position, Eigen::Vector3d(-1.5, 1, 4));
  EXPECT_EQ(views[0].low, Eigen::Vector2d(-3, -2));
  EXPECT_EQ(views[0].high, Eigen::Vector2d(0.2, 0.2));
  EXPECT_EQ(views[3].low, Eigen::Vector2d(-0.2, -0.2));
  EXPECT_EQ(views[3].high, Eigen::Vector2d(3, 2));
  // Every point inside the walls is seen; within 0.2 m of a seam by two, at the centre by four.
  auto seen_by = [&](double x, double y) {
    int n = 0;
    for (const CameraView& v : views) n += v.Sees(x, y) ? 1 : 0;
    return n;
  };
  for (double x = -3; x <= 3; x += 0.25)
    for (double y = -2; y <= 2; y += 0.25) EXPECT_GE(seen_by(x, y), 1) << x << " " << y;
  EXPECT_EQ(seen_by(0.1, 1.5), 2);
  EXPECT_EQ(seen_by(0.3, 1.5), 1);
  EXPECT_EQ(seen_by(0, 0), 4);
  EXPECT_EQ(seen_by(2.9, -1.9), 1);
}

TEST(CameraLayout, TheScenesCamerasAreReadAndChecked) {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string robots = "duration: 1\nrobots:\n  - {name: a, model: " + model +
                             ", commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}}\n";
  const Scene s = LoadSceneFromString("name: c\n" + robots + "cameras: {columns: 4, rows: 2, overlap: 0.5, height: 5}\n",
                                      "c.yaml", ".");
  ASSERT_TRUE(s.cameras);
  EXPECT_EQ(s.cameras->columns, 4);
  EXPECT_EQ(s.cameras->rows, 2);
  EXPECT_EQ(s.cameras->overlap, 0.5);
  EXPECT_EQ(s.cameras->height, 5);
  EXPECT_FALSE(LoadSceneFromString("name: c\n" + robots, "c.yaml", ".").cameras);
  const std::string bad = testing::SceneError("name: c\n" + robots + "cameras: {columns: 0, colour: red}\n");
  EXPECT_NE(bad.find(":5:"), std::string::npos) << bad;
  EXPECT_NE(bad.find("columns"), std::string::npos) << bad;
  EXPECT_NE(bad.find("unknown key 'colour'"), std::string::npos) << bad;
}

// Three robots: blue 0 at the centre (all four cameras), blue 1 deep in camera 3's
// quadrant, yellow 0 on the seam between cameras 0 and 1; the ball near camera 2's
// corner. Lockstep, blue waited for, 20 frames.
std::string CameraScene(bool cameras) {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string hold = "commands: {type: sequence, segments: [{duration: 1, command: [0.3, 0, 0.5]}]}";
  return "name: cams\nbackend: analytic\nframe_rate: 60\nduration: 10\nseed: 11\n"
         "ball: {start: {x: -2, y: 1.5}, vision: {noise_xy: 0.003, drop_probability: 0.0}}\n" +
         std::string(cameras ? "cameras: {columns: 2, rows: 2, overlap: 0.4}\n" : "") +
         "robots:\n"
         "  - {name: b0, model: " + model + ", start: {x: 0, y: 0}, " + hold + "}\n"
         "  - {name: b1, model: " + model + ", start: {x: 2, y: 1.5}, " + hold + "}\n"
         "  - {name: y0, team: yellow, model: " + model + ", start: {x: 0.05, y: -1.5}, " + hold + "}\n";
}

struct Served {
  SimulationResult result;
  std::vector<SSL_WrapperPacket> packets;  // every detection packet, in arrival order
};

Served Serve(const Scene& scene, int frames) {
  UdpSocket vision("127.0.0.1", 0), client("127.0.0.1", 0);
  ServeOptions o;
  o.control_port = o.blue_port = o.yellow_port = 0;
  o.vision_port = vision.port();
  o.lockstep = true;
  o.teams = {"blue"};
  o.max_frames = frames;
  LiveField field(scene, MakeSimulation(scene, "analytic"), o);
  std::thread server([&] { field.Run([] { return false; }); });
  Served out;
  std::uint32_t answered = 0;  // frames answered so far
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (answered < static_cast<std::uint32_t>(frames) && std::chrono::steady_clock::now() < end) {
    std::optional<Datagram> d = vision.Receive(65536);
    if (!d) {
      WaitReadable({&vision}, 0.05);
      continue;
    }
    SSL_WrapperPacket p;
    if (!p.ParseFromString(d->bytes) || !p.has_detection()) continue;
    out.packets.push_back(p);
    // Answer a frame once the last camera's packet of it is in.
    if (p.detection().camera_id() + 1 == (scene.cameras ? 4u : 1u) && p.detection().frame_number() == answered) {
      RobotControl control;
      control.add_robot_commands()->set_id(0);
      client.SendTo(control.SerializeAsString(), UdpEndpoint{ParseIpv4("127.0.0.1"), field.blue_port()});
      ++answered;
    }
  }
  server.join();
  out.result = field.result();
  return out;
}

TEST(Cameras, EachCameraSendsWhatItsAreaHoldsWithItsOwnNoise) {
  const Scene scene = LoadSceneFromString(CameraScene(true), "cams.yaml", ".");
  const Served served = Serve(scene, 20);
  const int delay = 2;  // omni4's vision_frames
  // Per frame, the four cameras' packets in id order; geometry with four calibrations.
  std::map<std::uint32_t, std::vector<SSL_DetectionFrame>> frames;
  int geometry = 0;
  for (const SSL_WrapperPacket& p : served.packets) {
    frames[p.detection().frame_number()].push_back(p.detection());
    if (p.has_geometry()) {
      ++geometry;
      EXPECT_EQ(p.geometry().calib_size(), 4);
      // Camera 3 above the centre of the +x, +y quadrant of the walls.
      EXPECT_EQ(p.geometry().calib(3).derived_camera_world_tx(), static_cast<float>(1000 * scene.field.length / 4));
      EXPECT_EQ(p.geometry().calib(3).derived_camera_world_ty(), static_cast<float>(1000 * scene.field.width / 4));
    }
  }
  EXPECT_GE(geometry, 1);
  ASSERT_GE(frames.size(), 20u);
  double differ = 0;
  int overlaps = 0;
  for (std::uint32_t k = delay; k < 20; ++k) {
    const std::vector<SSL_DetectionFrame>& f = frames[k];
    ASSERT_EQ(f.size(), 4u) << "frame " << k;
    for (std::uint32_t c = 0; c < 4; ++c) {
      EXPECT_EQ(f[c].camera_id(), c);
      EXPECT_EQ(f[c].t_capture(), f[0].t_capture());
    }
    // blue 0 at the centre: all four; blue 1: camera 3 only; yellow 0 (x 0.05): cameras 0 and 1.
    auto blue = [&](int c, unsigned id) -> const SSL_DetectionRobot* {
      for (const SSL_DetectionRobot& r : f[static_cast<std::size_t>(c)].robots_blue())
        if (r.robot_id() == id) return &r;
      return nullptr;
    };
    const Pose2& truth0 = served.result.frames[0][k - delay].truth;
    for (int c = 0; c < 4; ++c) {
      const SSL_DetectionRobot* r = blue(c, 0);
      ASSERT_NE(r, nullptr) << "camera " << c << " frame " << k;
      EXPECT_NEAR(r->x() / 1000, truth0.x, 0.005) << c;  // omni4: 1 mm of noise
      EXPECT_NEAR(r->y() / 1000, truth0.y, 0.005) << c;
      EXPECT_EQ(blue(c, 1) != nullptr, c == 3) << "camera " << c << " frame " << k;
      EXPECT_EQ(f[static_cast<std::size_t>(c)].robots_yellow_size(), c < 2 ? 1 : 0) << c;
      EXPECT_EQ(f[static_cast<std::size_t>(c)].balls_size(), c == 2 ? 1 : 0) << c;
    }
    differ += std::abs(blue(0, 0)->x() - blue(1, 0)->x());
    ++overlaps;
  }
  EXPECT_GT(differ / overlaps, 0.2) << "mm: two cameras' noise should be independent";
}

TEST(Cameras, TheObserversLogsAreAsWithOneCameraAndTheCamerasAreDeterministic) {
  const Served one = Serve(LoadSceneFromString(CameraScene(false), "one.yaml", "."), 20);
  const Served four = Serve(LoadSceneFromString(CameraScene(true), "four.yaml", "."), 20);
  const Served again = Serve(LoadSceneFromString(CameraScene(true), "four.yaml", "."), 20);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_EQ(one.result.frames[i].size(), four.result.frames[i].size());
    for (std::size_t k = 0; k < one.result.frames[i].size(); ++k) {
      EXPECT_EQ(one.result.frames[i][k].seen.x, four.result.frames[i][k].seen.x) << i << " " << k;
      EXPECT_EQ(one.result.frames[i][k].truth.y, four.result.frames[i][k].truth.y) << i << " " << k;
    }
  }
  ASSERT_EQ(four.packets.size(), again.packets.size());
  for (std::size_t p = 0; p < four.packets.size(); ++p)
    EXPECT_EQ(four.packets[p].SerializeAsString(), again.packets[p].SerializeAsString()) << p;
}

}  // namespace
}  // namespace twinsim
