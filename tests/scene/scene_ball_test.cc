// A scene's optional ball (docs/scenes.md, docs/ball.md): read and checked with
// file:line, run beside the robots on each engine, written as ball.csv and drawn in the
// path plot; scenes without it run exactly as before.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "io/output_files.h"
#include "scene/scene.h"
#include "scene/scene_plots.h"
#include "scene/scene_run.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

// One robot standing still at the origin facing +x; the ball rolls at it from 1 m.
std::string BallScene(const std::string& ball) {
  return "name: ball\nbackend: ode\nframe_rate: 60\nduration: 2\nrobots:\n"
         "  - {name: keeper, model: ../models/omni4.yaml, start: {x: 0, y: 0}, "
         "commands: {type: sequence, segments: [{duration: 1, command: [0, 0, 0]}]}}\n"
         "plots: [{type: path, file: path.png}]\n" + ball;
}

std::string BallSceneErrorOf(const std::string& yaml) { return testing::SceneError(yaml); }

TEST(SceneBall, ShippedBallScenesLoad) {
  for (const char* name : {"ball_bounce", "serve_2v2_ball"}) {
    const Scene s = LoadScene(SourcePath(std::string("scenes/") + name + ".yaml"));
    EXPECT_TRUE(s.ball.has_value()) << name;
  }
  EXPECT_FALSE(LoadScene(SourcePath("scenes/serve_2v2.yaml")).ball.has_value());
}

TEST(SceneBall, NoBallSectionNoBall) {
  const Scene s = LoadSceneFromString(BallScene(""), "s.yaml", SourcePath("scenes"));
  EXPECT_FALSE(s.ball.has_value());
  const SimulationResult r = RunOmniScene(s, "analytic", "");
  EXPECT_TRUE(r.ball.empty());
}

TEST(SceneBall, TheBallsParametersAndStartAreRead) {
  const Scene s = LoadSceneFromString(
      BallScene("ball: {radius: 0.02, mass: 0.05, sliding_friction: 0.3, rolling_friction: 0.04, restitution: 0.6,\n"
                "       floor_restitution: 0.4, robot_friction: 0.2, drag: 0, start: {x: 1, y: 0.1, vx: -2}}\n"),
      "s.yaml", SourcePath("scenes"));
  ASSERT_TRUE(s.ball.has_value());
  EXPECT_EQ(s.ball->model.radius, 0.02);
  EXPECT_EQ(s.ball->model.mass, 0.05);
  EXPECT_EQ(s.ball->model.sliding_friction, 0.3);
  EXPECT_EQ(s.ball->model.rolling_friction, 0.04);
  EXPECT_EQ(s.ball->model.restitution, 0.6);
  EXPECT_EQ(s.ball->model.floor_restitution, 0.4);
  EXPECT_EQ(s.ball->model.robot_friction, 0.2);
  EXPECT_EQ(s.ball->model.drag, 0);
  EXPECT_EQ(s.ball->start.position, Eigen::Vector3d(1, 0.1, 0.02));  // on the floor unless z says
  EXPECT_EQ(s.ball->start.velocity, Eigen::Vector3d(-2, 0, 0));
  const Scene d = LoadSceneFromString(BallScene("ball: {}\n"), "s.yaml", SourcePath("scenes"));
  EXPECT_EQ(d.ball->model.radius, 0.0215);
  EXPECT_EQ(d.ball->model.mass, 0.046);
}

TEST(SceneBall, BadValuesAreReportedWithFileAndLine) {
  const std::string e = BallSceneErrorOf(BallScene("ball:\n  radius: -0.02\n  mass: 0\n  restitution: 1.2\n  drag: abc\n"
                                          "  colour: white\n  start: {x: 9, z: 0.001}\n"));
  EXPECT_NE(e.find("s.yaml:9:"), std::string::npos) << e;   // radius
  EXPECT_NE(e.find("s.yaml:10:"), std::string::npos) << e;  // mass
  EXPECT_NE(e.find("s.yaml:11:"), std::string::npos) << e;  // restitution
  EXPECT_NE(e.find("s.yaml:12:"), std::string::npos) << e;  // drag
  EXPECT_NE(e.find("unknown key 'colour'"), std::string::npos) << e;
  EXPECT_NE(e.find("s.yaml:14:"), std::string::npos) << e;  // z below the radius
  const std::string camera = BallSceneErrorOf(BallScene("ball:\n  vision:\n    noise_xy: -0.001\n    drop_probability: 1.5\n"
                                               "    noise_z: .nan\n    blur: 1\n"));
  EXPECT_NE(camera.find("s.yaml:10:"), std::string::npos) << camera;  // noise_xy
  EXPECT_NE(camera.find("s.yaml:11:"), std::string::npos) << camera;  // drop_probability
  EXPECT_NE(camera.find("s.yaml:12:"), std::string::npos) << camera;  // noise_z
  EXPECT_NE(camera.find("unknown key 'blur'"), std::string::npos) << camera;
  const std::string outside = BallSceneErrorOf(BallScene("ball: {start: {x: 9}}\n"));
  EXPECT_NE(outside.find("s.yaml:8:"), std::string::npos) << outside;
  EXPECT_NE(outside.find("outside the"), std::string::npos) << outside;
}

TEST(SceneBall, TheRunWritesTheBallsPathAndItBouncesOffTheRobot) {
  for (const std::string& backend : {std::string("ode"), std::string("bullet"), std::string("analytic")}) {
    const Scene s = LoadSceneFromString(
        BallScene("ball: {drag: 0, restitution: 0.5, start: {x: 1, y: 0, vx: -2}}\n"), "s.yaml", SourcePath("scenes"));
    const SimulationResult r = RunOmniScene(s, backend, "");
    ASSERT_EQ(r.ball.size(), r.frames[0].size());
    EXPECT_EQ(r.ball.front().truth.position.x(), 1);
    // It reaches the front (0.073 m + radius) and bounces back (it only ever came in).
    double nearest = 1, fastest_out = 0;
    for (const BallRecord& b : r.ball) {
      nearest = std::min(nearest, b.truth.position.x());
      fastest_out = std::max(fastest_out, b.truth.velocity.x());
    }
    EXPECT_NEAR(nearest, testing::Omni4().FrontDistance() + 0.0215, 0.005) << backend;
    EXPECT_GT(fastest_out, 0.3) << backend;

    const std::string dir = testing::TempDir("scene_ball_" + backend);
    OutputFiles files(dir);
    WriteOmniRunFiles(s, r, false, &files);
    const std::string csv = testing::ReadText(dir + "/ball.csv");
    EXPECT_EQ(csv.substr(0, csv.find('\n')), "t,x,y,z,vx,vy,vz");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(r.ball.size()) + 1);
    // The same scene gives the same bytes.
    const SimulationResult again = RunOmniScene(s, backend, "");
    EXPECT_EQ(BallCsv(again.ball), csv) << backend;

    const PathPlot plot = ScenePathPlot(s.plots[0], s, r, backend);
    ASSERT_FALSE(plot.paths.empty());
    EXPECT_EQ(plot.paths.back().name, "ball");
    EXPECT_EQ(plot.paths.back().poses.size(), r.ball.size());
  }
}

TEST(SceneBall, RestoringAndSteppingGivesTheSameBallAsSteppingOn) {
  for (const std::string& backend : {std::string("ode"), std::string("bullet")}) {
    const Scene s = LoadSceneFromString(BallScene("ball: {start: {x: 0.6, y: 0.02, vx: -2}}\n"), "s.yaml",
                                        SourcePath("scenes"));
    Simulation sim = MakeSimulation(s, backend);
    for (int k = 0; k < 20; ++k) sim.Step();
    const SimulationState saved = sim.Save();
    std::vector<BallState> first, second;
    for (int k = 0; k < 40; ++k) {  // through the bounce
      sim.Step();
      first.push_back(sim.ball()->ball());
    }
    sim.Restore(saved);
    for (int k = 0; k < 40; ++k) {
      sim.Step();
      second.push_back(sim.ball()->ball());
    }
    for (std::size_t k = 0; k < first.size(); ++k) {
      EXPECT_EQ(first[k].position, second[k].position) << backend << " frame " << k;
      EXPECT_EQ(first[k].velocity, second[k].velocity) << backend << " frame " << k;
      EXPECT_EQ(first[k].spin, second[k].spin) << backend << " frame " << k;
    }
  }
}

TEST(SceneBall, TheFlatFrontAndTheKickerAndDribblerAreModelKeysWithDefaults) {
  const OmniModel d = testing::Omni4();
  EXPECT_EQ(d.front_distance, 0);
  EXPECT_NEAR(d.FrontDistance(), 0.82 * d.chassis_radius, 1e-12);
  EXPECT_EQ(d.kicker_max_speed, 6.5);
  EXPECT_EQ(d.dribbler_max_force, 1.0);
  const std::string path = testing::WriteText(
      testing::TempDir("ball_model") + "/m.yaml",
      "extends: " + SourcePath("models/omni4.yaml") +
          "\nname: m\nchassis: {front_distance: 0.07}\nkicker: {max_speed: 8}\ndribbler: {max_force: 2}\n");
  const OmniModel m = LoadOmniModel(path);
  EXPECT_EQ(m.FrontDistance(), 0.07);
  EXPECT_EQ(m.kicker_max_speed, 8);
  EXPECT_EQ(m.dribbler_max_force, 2);
  try {
    LoadOmniModelFromString("name: m\nchassis: {front_distance: 0.2}\nwheels: {angles_deg: [45, 135, 225, 315]}\n"
                            "kicker: {max_speed: -1}\n", "m.yaml");
    FAIL() << "expected an input error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("m.yaml:2:"), std::string::npos) << what;
    EXPECT_NE(what.find("front_distance"), std::string::npos) << what;
    EXPECT_NE(what.find("m.yaml:4:"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace twinsim
