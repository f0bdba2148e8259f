// The nominal physical model's step over one or more samples: what a residual ("hybrid")
// arm predictor (learning/arm_predictor.h) starts from before adding its learned
// correction.
//
// It is exactly the step of the physical nominal candidate of the arm-learning
// comparison: the arm simulation loop (sim/arm_simulation.h) over the model on the
// analytic backend (rigid-body forward dynamics by RK4 at the backend's default step),
// with the model's nominal viscous and Coulomb friction solved at velocity level (a
// joint sticks exactly when Coulomb friction can hold it within the sample; viscous
// friction is trapezoidal) and any effects the model file names. Only the command delay
// line is taken out: the torques passed in are the ones that act (arm_features.h), the
// delay having been applied already. So the same deterministic function serves in
// training and in use, and a residual predictor with a zero correction moves exactly as
// the nominal physical model does. Effects with memory of their own (time_delay,
// joint_flexibility's motor state) start afresh at every call: the step is then an
// approximation of the loop's, still deterministic.
//
// One-sample steps are remembered for the last few (q, qd, tau) asked: a residual
// predictor with the nominal errors as inputs asks for the same transitions again as its
// window slides, and the answer is the same bits either way.
//
//   ArmNominalStep nominal(model);
//   nominal.Step(q, qd, tau, 1, q_next, qd_next);
#pragma once

#include <memory>
#include <vector>

#include "robots/arm/arm_model.h"
#include "sim/arm_simulation.h"

namespace twinsim {

class ArmNominalStep {
 public:
  // Throws InputError for a model that does not Validate().
  explicit ArmNominalStep(const ArmModel& model);

  // The model given (with its delay; the step itself runs without it).
  const ArmModel& model() const { return model_; }

  // The state `samples` samples after (q, qd) (dof each) under the torques `tau`
  // (samples x dof, row-major; row k acts over sample k): into q_later, qd_later (dof
  // each). Throws CheckFailed when the model runs away.
  void Step(const double* q, const double* qd, const double* tau, int samples, double* q_later, double* qd_later);

 private:
  ArmModel model_;
  std::unique_ptr<ArmSimulation> sim_;  // over the model without its command delay
  Eigen::VectorXd q_, qd_, tau_;        // dof, scratch
  // The last one-sample steps: key (q, qd, tau) and value (q_later, qd_later), a ring.
  std::vector<std::vector<double>> keys_, values_;
  std::size_t next_ = 0;
};

}  // namespace twinsim
