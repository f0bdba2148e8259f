// An arm scene: a plant arm (a model file with its effects), a task that gives the joint
// reference (the writing task of seed 001, a hold, a step, a sinusoid, or seeded random
// motion to record training data), a tracking
// controller with its own model "hat" (which may differ from the plant), the default
// backend, and the plots `twinsim run` draws. A scene file is an arm scene when its top
// level says `robot: arm` (SceneRobotKind); the schema is in docs/scenes.md.
//
// Loaded from YAML into plain structs and validated as a whole (unknown keys, types,
// ranges, both models, joint counts and sample times), every problem reported as
// "path:line:column: ..." at once. ArmSceneReference() then gives the joint reference
// and RunTrackingTrial (control/computed_torque.h) runs it:
//
//   ArmScene scene = LoadArmScene("scenes/rrr_writing.yaml");
//   ArmReference ref = ArmSceneReference(scene);
//   TrackingTrial trial = RunTrackingTrial(scene.plant, scene.hat, ref, scene.tracking);
//   std::string csv = ArmSceneTrajectoryCsv(scene, trial);  // as the `sensors:` record it
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "control/arm_trials.h"
#include "control/closed_loop_frf.h"
#include "control/computed_torque.h"
#include "control/iterative_learning.h"
#include "control/writing_task.h"
#include "core/robot_kind.h"
#include "robots/arm/arm_model.h"
#include "scene/arm_sensors.h"
#include "scene/scene_overrides.h"

namespace twinsim {

// Where the joint reference comes from.
struct ArmTaskSpec {
  std::string type = "writing";  // writing | hold | step | sinusoid | random
  WritingTaskOptions writing;    // type writing (its `tool` is also the plots' tool point)
  // type random: seeded random motion to learn from (control/arm_trials.h), a multi-sine
  // or stop-and-go moves around training.center +- training.amplitude for `duration`
  // (training.seconds); the scene's seed picks the motion and the controller's dither.
  std::string motion = "stop_and_go";  // multisine | stop_and_go
  TrainingTrialOptions training;
  // hold, step, sinusoid: the reference starts at q (rad or m, one per joint) and lasts
  // `duration`; step jumps to `to` at `at`; sinusoid adds amplitude * sin(2 pi f t).
  Eigen::VectorXd q, to, amplitude;
  double duration = 2;     // s
  double at = 0.5;         // s, the step's time
  double frequency = 1;    // Hz, the sinusoid's
};

// One PNG `twinsim run` draws for an arm scene.
struct ArmPlotSpec {
  // tool_path: the tool point's path in the writing plane (base y-z, seen from behind
  //   the arm), reference vs realised;
  // joint_torques: per joint, the controller's output beside the model's torque and the
  //   effort limit over time (one PNG per joint, `_joint<j>` before .png);
  // tracking_error: q_ref - q of every joint over time.
  std::string type;
  std::string file;   // a plain file name ending in .png
  int width = 1200;   // px
  int height = 700;   // px
  std::string title;  // "{scene}", "{backend}" replaced; empty: a title naming the plot
};

// The `ilc:` block: iterative learning control trials (`twinsim ilc`,
// control/iterative_learning.h) and how the process sensitivity is measured for the
// learning filter (control/closed_loop_frf.h).
struct IlcSpec {
  bool present = false;               // the scene has an `ilc:` block
  IlcOptions options;                 // trials, gain, q_order, q_cutoff
  std::string learning_filter = "fitted";  // fitted (to the measured FRF) | model (the controller's model)
  FrfOptions frf;                     // period, periods, band, amplitude (seed: the scene's)
  // rad or m, one per joint each; empty: the seed's 16, a 4 x 4 grid over joints 2 and
  // 3 across the range the task moves them through, the waist at the task's start
  // (GridPostures; arms of fewer joints: 4 postures along the task's reference).
  std::vector<Eigen::VectorXd> postures;
  // The plant fit behind a "fitted" learning filter (ilc.frf's fit_band, max_shift,
  // coherence, model_order).
  PlantFitOptions fit;
  // q_cutoff: auto (the default): each joint's highest cutoff meeting the convergence
  // criterion at every posture (AutoQCutoff); a number: that cutoff for every joint.
  bool q_cutoff_auto = true;
};

struct ArmScene {
  std::string path;
  std::string name;
  std::string backend = "analytic";  // analytic | ode | bullet | learned; `twinsim run --backend` overrides
  std::uint64_t seed = 1;            // the random task's motion and the controller's dither
  std::string plant_path, hat_path;  // as resolved (relative to the scene file)
  ArmModel plant;                    // the arm simulated, with its effects
  ArmModel hat;                      // the controller's model (default: the plant's file)
  ArmTaskSpec task;
  TrackingOptions tracking;          // controller, gains, compensation; backend set by run
  std::vector<ArmPlotSpec> plots;
  IlcSpec ilc;
  ArmSensorSpec sensors;             // what trajectory.csv records (default: exact q, qd, command)
};

// An arm when the scene file's top level has `robot: arm`, else omni. Throws InputError
// when the file cannot be read or `robot` names another kind.
RobotKind SceneRobotKind(const std::string& path);

// Loads and validates an arm scene and the models it names; throws InputError listing
// every problem as "path:line:column: ...".
ArmScene LoadArmScene(const std::string& path);
// As LoadArmScene, with keys of the scene and of its plant's model set from outside.
ArmScene LoadArmScene(const std::string& path, const SceneOverrides& overrides);
ArmScene LoadArmSceneFromString(const std::string& yaml, const std::string& name, const std::string& base_dir);

// The scene's joint reference at the plant's sample time. Throws InputError (naming
// the scene) when the writing task cannot be drawn by the hat model's arm (out of
// reach, beyond a limit, not a waist-shoulder-elbow arm).
ArmReference ArmSceneReference(const ArmScene& scene);

// The text of `trajectory.csv` for a trial of the scene: the contract's arm log as the
// scene's `sensors:` record it (SensedArmLog with scene.seed), byte for byte the exact
// `t,q,tau,qd,qref` log when the block is absent. Throws InputError when the
// block's per-joint values do not match the trial's joint count.
std::string ArmSceneTrajectoryCsv(const ArmScene& scene, const TrackingTrial& trial);

// The postures the ILC's frequency responses are measured at: scene.ilc.postures, or
// 4 along `reference` (its first and last sample and two evenly in between).
std::vector<Eigen::VectorXd> IlcPostures(const ArmScene& scene, const ArmReference& reference);

}  // namespace twinsim
