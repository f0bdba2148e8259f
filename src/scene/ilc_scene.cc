#include "scene/ilc_scene.h"

#include <chrono>

#include "core/error.h"
#include "scene/scene_run.h"

namespace twinsim {

IlcSceneRun RunIlcScene(ArmScene scene, const std::string& backend, int trials, const IlcSceneCallbacks& callbacks,
                        const std::string& predictor) {
  IlcSceneRun run;
  run.backend = backend.empty() ? scene.backend : backend;
  run.reference = ArmSceneReference(scene);
  run.tracking = scene.tracking;
  run.tracking.backend = run.backend;
  // Every trial and FRF run builds its plant's backend with these: the scene's factory.
  run.tracking.backend_options = ArmSceneBackendOptions(scene, run.backend, predictor);
  run.tracking.dither = 0;  // learning needs the trials to repeat
  const IlcSpec& spec = scene.ilc;
  const int n = scene.plant.dof();
  const auto start = std::chrono::steady_clock::now();

  // 1. The process sensitivity at the postures.
  run.postures = IlcPostures(scene, run.reference);
  run.frf = MeasureProcessSensitivity(scene.plant, scene.hat, run.postures, run.tracking, spec.frf,
                                      callbacks.frf_progress);
  run.frf_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // 2. The learning filters: the controller's feedback is known; "fitted" adds the
  // plant's inertia and delay fitted to the nominal response, "model" the model's.
  Eigen::VectorXd mean_posture = Eigen::VectorXd::Zero(n);
  for (const Eigen::VectorXd& p : run.postures) mean_posture += p / static_cast<double>(run.postures.size());
  const Eigen::VectorXd q_start = run.reference.q.row(0).transpose();
  for (int j = 0; j < n; ++j) {
    const LearningFilter model = ModelLearningFilter(scene.hat, run.tracking, mean_posture, q_start, j);
    if (spec.learning_filter == "model") {
      run.filters.push_back(model);
      continue;
    }
    try {
      run.filters.push_back(
          FitPlantLearningFilter(run.frf, j, model, scene.hat.joints[static_cast<std::size_t>(j)].viscous, spec.fit));
    } catch (const InputError& e) {
      throw InputError(SourceLocation{scene.path}, std::string("ilc.frf.fit_band: ") + e.what());
    }
  }

  // The robustness filter: each joint's highest cutoff that meets the convergence
  // criterion at every measured posture, or the scene's.
  run.options = spec.options;
  if (trials >= 0) run.options.trials = trials;
  if (spec.q_cutoff_auto && spec.options.q_order > 0) {
    for (int j = 0; j < n; ++j) {
      try {
        run.options.q_cutoffs.push_back(AutoQCutoff(run.frf, j, run.filters[static_cast<std::size_t>(j)], spec.options));
      } catch (const InputError& e) {
        throw InputError(SourceLocation{scene.path}, std::string("ilc.q_cutoff: auto: ") + e.what());
      }
    }
  }
  if (callbacks.filters_ready) callbacks.filters_ready(run);

  // 3. The trials.
  run.result = RunIlc(scene.plant, scene.hat, run.reference, run.tracking, run.filters, run.options,
                      callbacks.trial_done);
  return run;
}

}  // namespace twinsim
