// Running a scene as `twinsim run` does, for every caller (the command, a batch job, a
// binding): build the backend `--backend`/`--predictor` name, run the whole scene, and
// write the files `run` writes into an output folder.
//
//   Scene scene = LoadScene("scenes/drive45.yaml");
//   SimulationResult result = RunOmniScene(scene, "ode", "");
//   OutputFiles files("out/drive45");
//   WriteOmniRunFiles(scene, result, /*plots=*/true, &files);
//
// Omni runs write trajectory.csv (the contract's log as the first robot's observer saw
// it: late, lost frames left out) and truth.csv (true pose and velocity every frame the robot is on the field),
// and the same with _NAME for every further robot, and ball.csv when the scene has a
// ball. Arm runs write trajectory.csv (the
// arm log as the scene's sensors record it) and tracking.csv (error, demand, model,
// applied and needed torque per joint). Plots are the scene's `plots:` list.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "control/computed_torque.h"
#include "io/output_files.h"
#include "scene/arm_scene.h"
#include "scene/scene.h"
#include "sim/arm_backend.h"
#include "robots/omni/omni_log.h"
#include "sim/omni_simulation.h"

namespace twinsim {

// The observer's log of one robot (a SimulationResult's frames): the frames whose
// observation arrived, at the time the camera stamped, with the pose seen and the
// command sent. What `run` writes as trajectory.csv.
std::vector<OmniLogRow> ObserverLog(const std::vector<FrameRecord>& frames);

// The ball's true path, one row per frame: `t,x,y,z,vx,vy,vz` (s, m, m/s, field frame;
// z the centre's height). What `run` writes as ball.csv when the scene has a ball.
std::string BallCsv(const std::vector<BallRecord>& ball);

// The run's files line by line, for logs written as the run goes (scene/run_log_stream.h):
// the headers, and one frame's line appended to *out (nothing where the file has no row
// for it: a lost observation, a robot off the field).
inline constexpr const char* kTruthHeader = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,vx,vy,omega\n";
inline constexpr const char* kBallHeader = "t,x,y,z,vx,vy,vz\n";
void AppendObserverRow(const FrameRecord& frame, std::string* out);  // trajectory.csv
void AppendTruthRow(const FrameRecord& frame, std::string* out);     // truth.csv
void AppendBallRow(const BallRecord& ball, std::string* out);        // ball.csv

// Runs every frame of an omni scene on `backend` ("learned" with the 1-frame predictor
// file `predictor`; empty: none). `progress(done, total)` is called as frames finish.
// Throws InputError for an unknown or uncompiled backend or an unreadable predictor,
// CheckFailed when the simulation diverges.
SimulationResult RunOmniScene(const Scene& scene, const std::string& backend, const std::string& predictor,
                              const std::function<void(int, int)>& progress = {});

// The backend an arm scene's plant runs on: `learned` steps the arm with `predictor`
// (an arm predictor from `twinsim train` for the scene's model), replacing the plant's
// bodies, friction and effects. Throws InputError for an unknown or uncompiled backend,
// a learned backend without a predictor or a predictor that does not fit, and a
// predictor given to another backend.
std::unique_ptr<ArmBackend> MakeArmSceneBackend(const ArmScene& scene, const std::string& backend,
                                                const std::string& predictor);
// What MakeArmSceneBackend builds the backend with (the learned one's predictor, loaded
// and checked against the scene's model), for procedures that build one per trial
// (TrackingOptions::backend_options: ILC). Throws as MakeArmSceneBackend.
ArmBackendOptions ArmSceneBackendOptions(const ArmScene& scene, const std::string& backend, const std::string& predictor);

// Runs an arm scene's task on `backend` (as MakeArmSceneBackend), the scene's seed
// picking the random motion and the controller's dither. Throws as MakeArmSceneBackend,
// ArmSceneReference and RunTrackingTrial.
TrackingTrial RunArmScene(const ArmScene& scene, const std::string& backend, const std::string& predictor);

// Writes what `twinsim run` writes for a finished run into `files`; the scene's PNGs
// (titled with result.backend) only when `plots` and rendering was compiled in. Throws
// InputError when a file cannot be written.
void WriteOmniRunFiles(const Scene& scene, const SimulationResult& result, bool plots,
                       OutputFiles* files);
// The scene's PNGs alone (where rendering was compiled in), for logs written otherwise
// (twinsim serve streams them: scene/run_log_stream.h).
void WriteOmniRunPlots(const Scene& scene, const SimulationResult& result, OutputFiles* files);
void WriteArmRunFiles(const ArmScene& scene, const TrackingTrial& trial, const std::string& backend, bool plots,
                      OutputFiles* files);

// The path length of robot `robot`'s true path (m): the sum of the distances between
// consecutive frames.
double TruePathLength(const SimulationResult& result, int robot);

}  // namespace twinsim
