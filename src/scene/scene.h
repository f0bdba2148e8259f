// A scene: which robots, on which field, driven by what, for how long, at which camera
// rate, on which backend, with which seed, and which plots `twinsim run` draws. Loaded
// from YAML (docs/scenes.md, docs/rendering.md) into plain structs, validated as a
// whole, and turned into a Simulation by MakeSimulation().
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "backends/omni_backend_factory.h"
#include "render/plot_spec.h"
#include "scene/camera_layout.h"
#include "scene/command_source.h"
#include "scene/scene_overrides.h"
#include "sim/omni_simulation.h"

namespace twinsim {

struct SceneRobot {
  std::string name;
  // Which team and robot id the league's protocol knows the robot by (twinsim serve,
  // docs/serve.md): `team: blue|yellow` (default blue) and `id` 0..15 (default: the
  // smallest of its team's ids not yet taken, in the order of the list).
  std::string team = "blue";
  int id = 0;
  std::string model_path;  // as resolved (relative paths are relative to the scene file)
  OmniModel model;
  Pose2 start;
  CommandSpec commands;
  // The robot's own backend (`backend:`, docs/scenes.md): analytic, ode, bullet or
  // learned; empty: the field's (the scene's `backend:` or --backend).
  std::string backend;
  // With `backend: learned`: its 1-frame predictor (`predictor:`, relative to the scene
  // file; as resolved) and the predictor loaded, checked against the model and the frame
  // rate. Robots naming the same file share one loaded predictor (and so one backend).
  std::string predictor_path;
  std::shared_ptr<const OmniPredictor> predictor;
  // `present: false`: the robot starts off the field (twinsim serve adds it with a
  // teleport's `present: true`; `twinsim run` keeps it off for the whole run).
  bool present = true;
};

// The ball of a scene (docs/scenes.md, docs/ball.md): its model and where it starts.
struct SceneBall {
  BallModel model;
  BallState start;    // default: at rest on the floor at the centre
  BallVision vision;  // the camera's noise and lost frames for the ball; default none
};

struct Scene {
  std::string path;
  std::string name;
  std::string backend = "ode";   // the field's: robots without their own `backend:` run on it; --backend overrides
  double frame_rate = 30;        // Hz
  int physics_substeps = 0;      // per frame; 0 = DefaultPhysicsSubsteps(frame_rate)
  double duration = 5;           // s
  std::uint64_t seed = 1;
  FieldModel field;
  std::vector<SceneRobot> robots;
  std::vector<PlotSpec> plots;   // PNGs `twinsim run` draws (docs/rendering.md)
  std::optional<SceneBall> ball; // the `ball:` section; none: a field without a ball
  // The `cameras:` section (scene/camera_layout.h): several cameras for twinsim serve;
  // none: one camera seeing the whole field, its detections what the observer receives.
  std::optional<CameraSetup> cameras;
  // run's and serve's --driving-noise: "on" every robot draws its driving noise, "off"
  // none, "model" as each model (or a learned robot's predictor) says.
  std::string driving_noise = "model";
  YAML::Node tune_pid;           // the `tune_pid:` block, read by ReadPidTuningOptions (tuning/pid_tuning.h)

  FrameTiming timing() const;
  // Number of frames from t = 0 to `duration` inclusive.
  int num_frames() const;
};

// Loads and validates a scene and the models it names; throws InputError listing every
// problem as "path:line:column: ...".
Scene LoadScene(const std::string& path);
// As LoadScene, with keys of the scene and of its robots' models set from outside.
Scene LoadScene(const std::string& path, const SceneOverrides& overrides);
Scene LoadSceneFromString(const std::string& yaml, const std::string& name, const std::string& base_dir);

// Replays a recorded match (`twinsim run --commands FILE`): every robot of `scene` is
// driven by its rows of the log at `path` (scene/command_log.h; commands.csv of `twinsim
// serve`), and the scene lasts until the log's last frame; robots that start off the
// field (`present: false`) stay off and need no rows. Throws InputError as
// ReadCommandLog (a robot without rows is named).
void ReplayCommandLog(const std::string& path, Scene* scene);

// The backend each robot of `scene` runs on when the field's is `field_backend` (the
// scene's `backend:` or --backend): its own `backend:` if it names one, else the field's.
std::vector<std::string> RobotBackends(const Scene& scene, const std::string& field_backend);

// The engine the ball runs on beside robots on `backend`: ode and bullet their own; the
// analytic and learned backends ODE (Bullet in a build without ODE).
std::string BallEngineFor(const std::string& backend);
// The same for robots on several backends (one name per robot): ODE when any robot runs
// on ode, else Bullet when any runs on bullet, else as for analytic. One backend for
// every robot gives what BallEngineFor(backend) gives.
std::string BallEngineFor(const std::vector<std::string>& backends);

// Builds the simulation of a scene, with the scene's ball if it has one. `backend` is the
// field's (the scene's `backend:` or --backend) and `options.predictor` its predictor:
// they apply to the robots that do not name their own. When every robot runs on the same
// backend this is exactly that backend (MakeOmniBackend(name, ...)); else one backend per
// group of robots (GroupedOmniBackend, docs/backends.md). `commands`, when given, makes
// robot i's command source instead of the scene's behaviour (Python's OmniSim drives
// them from outside).
//
// A robot on the learned backend whose predictor carries a driving noise (`train` fits
// one: analysis/learned_noise.h) draws that noise in place of its model's, as the
// scene's `driving_noise` says (SimulatedRobotModel).
using CommandSourceFactory = std::function<std::unique_ptr<CommandSource>(std::size_t robot)>;
Simulation MakeSimulation(const Scene& scene, const std::string& backend, const OmniBackendOptions& options = {},
                          const CommandSourceFactory& commands = {});

// The backend robot `robot` of `scene` runs on: its own `backend:` and `predictor:`, or
// the field's `backend` and `options.predictor`.
RobotBackendChoice RobotChoice(const SceneRobot& robot, const std::string& backend, const OmniBackendOptions& options);

// The model robot `robot` is simulated with on `choice`: its own, or on the learned
// backend with a predictor that carries a driving noise, that noise in place of the
// model's; its driving noise drawn as the scene's `driving_noise` says ("model": as the
// model, or that predictor, says).
OmniModel SimulatedRobotModel(const Scene& scene, const SceneRobot& robot, const RobotBackendChoice& choice);

}  // namespace twinsim
