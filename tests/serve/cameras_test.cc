// Several cameras (scene `cameras:`, scene/camera_layout.h, docs/serve.md "Several
// cameras"): a grid of overlapping views, each camera sending its own detection frames
// with its own noise; objects in an overlap seen by each camera that sees them; the
// observer's logs as without cameras.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <thread>

#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "scene/camera_layout.h"
#include "scene/scene.h"
#include "serve/camera_rig.h"
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
  EXPECT_EQ(s.cameras->grid.columns, 4);
  EXPECT_EQ(s.cameras->grid.rows, 2);
  EXPECT_EQ(s.cameras->grid.overlap, 0.5);
  EXPECT_EQ(s.cameras->grid.height, 5);
  EXPECT_TRUE(s.cameras->placements.empty());
  EXPECT_FALSE(s.cameras->staggered);
  EXPECT_FALSE(LoadSceneFromString("name: c\n" + robots, "c.yaml", ".").cameras);
  const std::string bad = testing::SceneError("name: c\n" + robots + "cameras: {columns: 0, colour: red}\n");
  EXPECT_NE(bad.find(":5:"), std::string::npos) << bad;
  EXPECT_NE(bad.find("columns"), std::string::npos) << bad;
  EXPECT_NE(bad.find("unknown key 'colour'"), std::string::npos) << bad;
}

TEST(CameraLayout, AListedCameraSeesItsFieldOfViewClippedToTheWalls) {
  FieldModel field;  // 10.4 x 7.4 m inside the walls
  CameraPlacement wide;
  wide.position = Eigen::Vector2d(-2, 0);
  wide.height = 2;
  wide.field_of_view = Eigen::Vector2d(90, 90);  // 2 m either way at 2 m up
  const CameraView v = PlacedCamera(wide, field);
  EXPECT_NEAR(v.low.x(), -4, 1e-12);
  EXPECT_NEAR(v.high.x(), 0, 1e-12);
  EXPECT_NEAR(v.low.y(), -2, 1e-12);
  EXPECT_NEAR(v.high.y(), 2, 1e-12);
  EXPECT_EQ(v.position, Eigen::Vector3d(-2, 0, 2));
  // The farthest corner lands on the nominal image's edge (290 pixels from the centre in y).
  EXPECT_NEAR(v.focal_length, 290, 1e-9);
  CameraPlacement given;
  given.position = Eigen::Vector2d(4, 0);
  given.area_low = Eigen::Vector2d(-1, -9);
  given.area_high = Eigen::Vector2d(9, 1);
  const CameraView a = PlacedCamera(given, field);
  EXPECT_EQ(a.low, Eigen::Vector2d(-1, -3.7));
  EXPECT_EQ(a.high, Eigen::Vector2d(5.2, 1));

  // Two cameras leaving a 2 m band across the middle unseen: 2 / 10.4 of the area.
  CameraSetup two;
  two.placements = {wide, wide};
  two.placements[0].field_of_view = Eigen::Vector2d(150, 170);
  two.placements[0].position = Eigen::Vector2d(-3.1, 0);  // sees x <= -3.1 + 2 tan 75 deg, beyond: -1 at 0.5631 m up
  two.placements[0].height = (3.1 - 1) / std::tan(75 * kPi / 180);
  two.placements[1] = two.placements[0];
  two.placements[1].position.x() = 3.1;
  const std::vector<CameraView> views = CameraViews(two, field, 60, 1);
  ASSERT_EQ(views.size(), 2u);
  EXPECT_EQ(views[1].id, 1);
  EXPECT_NEAR(views[0].high.x(), -1, 1e-9);
  EXPECT_NEAR(UnseenShare(views, field), 2 / 10.4, 0.002);
  EXPECT_EQ(UnseenShare(CameraViews(CameraGrid{2, 2, 0.4, 4}, field), field), 0);
}

TEST(CameraLayout, TheLeaguesLayoutsAndStaggeredClocks) {
  FieldModel field;
  field.length = 13.4;
  field.width = 10.4;
  CameraSetup a;
  a.grid = *LeagueCameraLayout("division_a");
  a.staggered = true;
  const std::vector<CameraView> views = CameraViews(a, field, 60, 7);
  ASSERT_EQ(views.size(), 8u);  // 4 x 2
  EXPECT_EQ(views[3].position, Eigen::Vector3d(3 * 13.4 / 8, -10.4 / 4, 6));
  EXPECT_EQ(UnseenShare(views, field), 0);
  // Camera i of 8 captures i/8 of a frame early; each numbers frames from its own start.
  std::set<std::uint32_t> starts;
  for (const CameraView& v : views) {
    EXPECT_NEAR(v.capture_lead, v.id / 8.0 / 60, 1e-15) << v.id;
    starts.insert(v.first_frame);
  }
  EXPECT_EQ(starts.size(), 8u);
  EXPECT_EQ(CameraViews(a, field, 60, 7)[5].first_frame, views[5].first_frame);  // from the seed
  EXPECT_EQ(LeagueCameraLayout("division_b")->columns * LeagueCameraLayout("division_b")->rows, 4);
  EXPECT_FALSE(LeagueCameraLayout("division_c"));
  a.staggered = false;
  for (const CameraView& v : CameraViews(a, field, 60, 7)) {
    EXPECT_EQ(v.capture_lead, 0);
    EXPECT_EQ(v.first_frame, 0u);
  }
}

TEST(CameraLayout, ListedCamerasAreReadAndChecked) {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string robots = "duration: 1\nrobots:\n  - {name: a, model: " + model +
                             ", commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}}\n";
  const Scene s = LoadSceneFromString("name: c\n" + robots +
                                          "cameras:\n  capture: staggered\n  list:\n"
                                          "    - {position: [-2.6, 0], height: 4.5, field_of_view: [70, 90]}\n"
                                          "    - {position: [2.6, 0], area: [-0.2, -3.7, 5.2, 3.7]}\n",
                                      "c.yaml", ".");
  ASSERT_TRUE(s.cameras);
  EXPECT_TRUE(s.cameras->staggered);
  ASSERT_EQ(s.cameras->placements.size(), 2u);
  EXPECT_EQ(s.cameras->placements[0].height, 4.5);
  EXPECT_EQ(*s.cameras->placements[0].field_of_view, Eigen::Vector2d(70, 90));
  EXPECT_FALSE(s.cameras->placements[1].field_of_view);
  EXPECT_EQ(s.cameras->placements[1].area_high, Eigen::Vector2d(5.2, 3.7));
  const Scene b = LoadSceneFromString("name: c\n" + robots + "cameras: {layout: division_b}\n", "c.yaml", ".");
  EXPECT_EQ(b.cameras->grid.columns, 2);
  EXPECT_EQ(b.cameras->grid.rows, 2);

  struct Bad {
    std::string cameras, says;
  };
  for (const Bad& bad : std::vector<Bad>{
           {"{layout: division_c}", "division_c"},
           {"{layout: division_a, columns: 3}", "a layout is a grid of its own"},
           {"{columns: 2, list: [{position: [0, 0], field_of_view: [60, 60]}]}", "take no layout or grid keys"},
           {"{list: []}", "1 to 16 cameras"},
           {"{list: }", "got nothing"},
           {"{list: [{position: [0, 0]}]}", "needs its field_of_view"},
           {"{list: [{position: [0, 0], field_of_view: [60, 60], area: [0, 0, 1, 1]}]}", "not both"},
           {"{list: [{position: [0, 0], area: [1, 0, 0, 1]}]}", "low < high"},
           {"{list: [{position: [0, 0], field_of_view: [180, 60]}]}", "field_of_view"},
           {"{list: [{position: [20, 0], area: [19, -1, 21, 1]}]}", "camera 0 sees nothing inside the walls"},
           {"{capture: sometimes}", "sometimes"},
       }) {
    const std::string message = testing::SceneError("name: c\n" + robots + "cameras: " + bad.cameras + "\n");
    EXPECT_NE(message.find(":5:"), std::string::npos) << bad.cameras << ": " << message;
    EXPECT_NE(message.find(bad.says), std::string::npos) << bad.cameras << ": " << message;
  }
  // One problem, one message: an inverted area is not also said to see nothing.
  const std::string inverted =
      testing::SceneError("name: c\n" + robots + "cameras: {list: [{position: [0, 0], area: [1, 0, 0, 1]}]}\n");
  EXPECT_EQ(inverted.find("sees nothing"), std::string::npos) << inverted;
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
  int answered = 0;  // frames answered so far
  std::optional<std::uint32_t> last_frame;  // the last camera's newest frame number
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (answered < frames && std::chrono::steady_clock::now() < end) {
    std::optional<Datagram> d = vision.Receive(65536);
    if (!d) {
      WaitReadable({&vision}, 0.05);
      continue;
    }
    SSL_WrapperPacket p;
    if (!p.ParseFromString(d->bytes) || !p.has_detection()) continue;
    out.packets.push_back(p);
    // Answer a frame once the last camera's packet of it is in (each camera numbers
    // frames by its own clock; a frame sent again is not answered twice).
    const std::uint32_t frame = p.detection().frame_number();
    if (p.detection().camera_id() + 1 == (scene.cameras ? 4u : 1u) && (!last_frame || frame > *last_frame)) {
      last_frame = frame;
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

// Issue 66: the served cameras draw as `run`'s camera does. A model whose camera
// repeats its last pose (repeat_probability 0.3) and stamps frames off the clock
// (time_jitter 2 ms): each camera repeats blue 0's pose on about 30 % of the frames
// (its own repeats: the cameras' streams are apart), and stamps its frames within 2 ms of
// the frame clock, each camera its own offset.
TEST(Cameras, EachCameraRepeatsPosesAndJittersItsStampsAsTheRecordedCameraDoes) {
  const std::string dir = testing::TempDir("camera_repeats");
  const std::string model = dir + "/repeating.yaml";
  {
    std::ofstream f(model);
    f << "extends: " << SourcePath("models/omni4.yaml")
      << "\nname: repeating\nvision: {noise_xy: 0.001, noise_theta: 0.005, repeat_probability: 0.3, time_jitter: 0.002}\n";
  }
  std::string text = CameraScene(true);
  const std::string omni4 = SourcePath("models/omni4.yaml");
  for (std::size_t at = text.find(omni4); at != std::string::npos; at = text.find(omni4)) text.replace(at, omni4.size(), model);
  const Served served = Serve(LoadSceneFromString(text, "cams.yaml", "."), 60);
  std::map<std::uint32_t, std::vector<SSL_DetectionFrame>> frames;
  for (const SSL_WrapperPacket& p : served.packets) frames[p.detection().frame_number()].push_back(p.detection());
  std::array<std::optional<std::pair<float, float>>, 4> last;
  std::array<int, 4> repeats{}, seen{};
  int stamps_apart = 0, stamped = 0;
  for (std::uint32_t k = 4; k < 60; ++k) {
    const std::vector<SSL_DetectionFrame>& f = frames[k];
    ASSERT_EQ(f.size(), 4u) << "frame " << k;
    const double clock = f[0].t_capture();
    for (std::size_t c = 0; c < 4; ++c) {
      // Every camera's stamp within 2 ms of camera 0's clock, one 2 ms either way.
      EXPECT_LE(std::abs(f[c].t_capture() - clock), 0.004 + 1e-9) << "frame " << k << " camera " << c;
      stamps_apart += f[c].t_capture() != clock;
      ++stamped;
      for (const SSL_DetectionRobot& r : f[c].robots_blue()) {
        if (r.robot_id() != 0) continue;
        const std::pair<float, float> xy{r.x(), r.y()};
        if (last[c]) repeats[c] += *last[c] == xy;
        ++seen[c];
        last[c] = xy;
      }
    }
  }
  EXPECT_GT(stamps_apart, stamped / 2);
  for (std::size_t c = 0; c < 4; ++c) {
    const double share = static_cast<double>(repeats[c]) / seen[c];
    EXPECT_GT(share, 0.12) << "camera " << c;  // 0.3 over 55 frames: 2.6 standard deviations below
    EXPECT_LT(share, 0.5) << "camera " << c;
  }
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

// A staggered capture between two frames: interpolated, the heading the short way round
// across +-pi, and never across a teleport (a jump no robot or ball makes in a frame).
TEST(Cameras, AStaggeredCaptureInterpolatesButNotAcrossATeleport) {
  const double dt = 1.0 / 60;
  const Pose2 p = CapturedPose(Pose2{1.0, 2.0, 0.5}, Pose2{0.98, 2.01, 0.4}, 0.25, dt);
  EXPECT_NEAR(p.x, 0.995, 1e-12);
  EXPECT_NEAR(p.y, 2.0025, 1e-12);
  EXPECT_NEAR(p.theta, 0.475, 1e-12);
  // Across the wrap: 3.1 now, -3.1 before (0.083 rad apart the short way).
  const Pose2 w = CapturedPose(Pose2{0, 0, 3.1}, Pose2{0, 0, -3.1}, 0.5, dt);
  EXPECT_NEAR(std::abs(w.theta), kPi, 1e-9);
  // 2 m in a frame (a teleport, or a robot parked off the field), and a turn of 2.5 rad
  // (150 rad/s): the frame's own pose.
  const Pose2 moved = CapturedPose(Pose2{1, 1, 0}, Pose2{3, 1, 0}, 0.5, dt);
  EXPECT_EQ(moved.x, 1);
  const Pose2 turned = CapturedPose(Pose2{1, 1, 0}, Pose2{1, 1, 2.5}, 0.5, dt);
  EXPECT_EQ(turned.theta, 0);
  // A kicked ball at 30 m/s is interpolated; one placed 2 m away is not.
  EXPECT_NEAR(CapturedBall(Eigen::Vector3d(0.5, 0, 0.02), Eigen::Vector3d(0, 0, 0.02), 0.5, dt).x(), 0.25, 1e-12);
  EXPECT_EQ(CapturedBall(Eigen::Vector3d(2, 0, 0.02), Eigen::Vector3d(0, 0, 0.02), 0.5, dt).x(), 2);
}

// Four staggered cameras over a robot driving at 1.5 m/s: camera c captures c/4 of a
// frame early, so it sees the robot where it was then (the true poses interpolated),
// stamps that instant, and numbers frames by its own clock.
TEST(Cameras, StaggeredCamerasCaptureEarlierAndCountTheirOwnFrames) {
  const std::string model = SourcePath("models/omni4.yaml");
  const std::string yaml = "name: fast\nbackend: analytic\nframe_rate: 60\nduration: 10\nseed: 5\n"
                           "cameras: {columns: 2, rows: 2, overlap: 0.4, capture: staggered}\n"
                           "robots:\n  - {name: b0, model: " + model + ", start: {x: -0.5, y: 0.01}, "
                           "commands: {type: sequence, segments: [{duration: 10, command: [1.5, 0, 0]}]}}\n";
  const Scene scene = LoadSceneFromString(yaml, "fast.yaml", ".");
  constexpr int kFrames = 60;
  const Served served = Serve(scene, kFrames);
  const Served again = Serve(scene, kFrames);
  const int delay = 2;  // omni4's vision_frames
  const double dt = 1.0 / 60;
  const std::vector<CameraView> views = CameraViews(*scene.cameras, scene.field, 60, scene.seed);
  const std::vector<FrameRecord>& truth = served.result.frames[0];
  std::array<double, 4> to_interpolated{}, to_frame{};
  std::array<int, 4> n{};
  for (const SSL_WrapperPacket& p : served.packets) {
    const SSL_DetectionFrame& f = p.detection();
    const CameraView& view = views.at(f.camera_id());
    const int k = static_cast<int>(f.frame_number() - view.first_frame);
    ASSERT_GE(k, 0) << "camera " << f.camera_id() << " frame " << f.frame_number();
    const int j = k - delay;  // the frame captured
    if (j < 1 || j >= static_cast<int>(truth.size())) continue;
    const double a = f.camera_id() / 4.0;
    EXPECT_NEAR(f.t_capture(), j * dt - a * dt, 1e-9) << f.camera_id();
    EXPECT_NEAR(f.t_sent(), k * dt, 1e-9);
    if (f.robots_blue_size() == 0) continue;  // not in this camera's area
    const Pose2& now = truth[static_cast<std::size_t>(j)].truth;
    const Pose2& before = truth[static_cast<std::size_t>(j - 1)].truth;
    const double x = f.robots_blue(0).x() / 1000, y = f.robots_blue(0).y() / 1000;
    const double xi = now.x + a * (before.x - now.x), yi = now.y + a * (before.y - now.y);
    to_interpolated[f.camera_id()] += std::hypot(x - xi, y - yi);
    to_frame[f.camera_id()] += std::hypot(x - now.x, y - now.y);
    ++n[f.camera_id()];
  }
  // The robot drives along y = 0.01 (within 0.2 m of the seam between the lower and the
  // upper cells) from x -0.5 across x = 0: every camera sees it for part of the run.
  // omni4's camera noise: 1 mm.
  for (int c = 0; c < 4; ++c) {
    ASSERT_GT(n[static_cast<std::size_t>(c)], 10) << c;
    EXPECT_LT(to_interpolated[static_cast<std::size_t>(c)] / n[static_cast<std::size_t>(c)], 0.002) << c;
  }
  // Camera 3 captures 3/4 of a frame early: about 19 mm behind the frame at 1.5 m/s.
  EXPECT_GT(to_frame[3] / n[3], 0.010);
  ASSERT_EQ(served.packets.size(), again.packets.size());
  for (std::size_t p = 0; p < served.packets.size(); ++p)
    EXPECT_EQ(served.packets[p].SerializeAsString(), again.packets[p].SerializeAsString()) << p;
}

}  // namespace
}  // namespace twinsim
