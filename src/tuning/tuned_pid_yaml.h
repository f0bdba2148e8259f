// The model file `twinsim tune-pid` writes (pid.yaml, docs/pid_tuning.md): the scene's
// robot with the learned controller, as a model file that `extends:` the robot's
// original model file (docs/models.md), so that it loads anywhere a model does and
// changes nothing but the name and the three PID controllers. A comment at the top says
// how it was learned. Written through yaml-cpp's emitter, numbers with 10 significant
// digits:
//
//   # PID parameters learned by `twinsim tune-pid scenes/tune_pid_zeros.yaml` on ode
//   # (policy gradient, seed 000 section 3.4): iteration 9 of 11, 210 test runs.
//   # Its test run: quality 0.81, distance 1.3 m, average speed 0.87 m/s, end deviation 1.2 %.
//   extends: ../../models/omni4.yaml
//   name: omni4_tuned
//   controller:
//     forward: {kp: 6.5, ki: 1.2, kd: 0.1, integral_limit: 2, output_limit: 20, slew_rate: 3}
//     ...
#pragma once

#include <string>

#include "tuning/pid_tuning.h"

namespace twinsim {

// The text of pid.yaml for `result` of tuning the scene of `evaluator`, to be written
// into the folder `out_dir`: `extends:` gives the robot's model file relative to it
// (absolute when no relative path exists).
std::string FormatTunedPidYaml(const TestRunEvaluator& evaluator, const PidTuningResult& result,
                               const std::string& out_dir);

}  // namespace twinsim
