// Iterative learning control of an arm scene (docs/ilc.md), the procedure `twinsim ilc`
// and the Python module run: measure the closed-loop process sensitivity at the scene's
// postures, build a learning filter per joint (fitted to the measurement, or the
// controller's model), then run the task trial after trial with the learned
// feedforward. The caller reports and writes (control/ilc_report.h).
//
//   IlcSceneRun run = RunIlcScene(LoadArmScene("scenes/rrr_writing_ilc.yaml"), "", -1);
//   std::printf("%s\n", run.result.BriefReport().c_str());
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "control/closed_loop_frf.h"
#include "control/iterative_learning.h"
#include "scene/arm_scene.h"

namespace twinsim {

struct IlcSceneRun {
  std::string backend;                  // the backend the trials ran on
  ArmReference reference;               // the task
  TrackingOptions tracking;             // the controller, without dither
  std::vector<Eigen::VectorXd> postures;
  ClosedLoopFrf frf;                    // process sensitivity per joint and posture
  double frf_seconds = 0;               // s, wall time of the measurement
  std::vector<LearningFilter> filters;  // per joint
  IlcOptions options;                   // the scene's, with the trials and each joint's Q cutoff as run
  IlcResult result;                     // the trials
};

struct IlcSceneCallbacks {
  std::function<void(int, int)> frf_progress;                          // (runs done, total)
  std::function<void(const IlcSceneRun&)> filters_ready;               // after the filters, before the trials
  std::function<void(int, const TrackingTrial&)> trial_done;           // each trial
};

// Runs ILC on `scene` on `backend` (empty: the scene's; `learned` with `predictor`, an arm
// predictor for the scene's model, built as `run` builds it: MakeArmSceneBackend) for
// `trials` learning trials (negative: the scene's). Throws InputError for a backend or
// predictor `run` would refuse, a fit band the measurement does not cover, an automatic
// Q cutoff that cannot meet the convergence criterion, and what the parts throw.
IlcSceneRun RunIlcScene(ArmScene scene, const std::string& backend, int trials, const IlcSceneCallbacks& callbacks = {},
                        const std::string& predictor = "");

}  // namespace twinsim
