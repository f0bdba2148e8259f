// The arm simulation loop: it owns simulated time and the command delay, and steps
// any ArmBackend (sim/arm_backend.h: the Newtonian one over analytic, ode or bullet with
// the arm's friction and effects, or the learned one) with the delayed commands.
//
// Time runs in samples of the model's sample_time Ts (1 ms for the RRR arm). At sample
// k (t_k = k Ts):
//   1. the loop samples the joints' q_k, qd_k (and stops with CheckFailed, naming the
//      joint, time and value, when they are not finite or run away);
//   2. the controller sends u_k = controller(t_k, q_k, qd_k), which is recorded;
//   3. u_k enters the command delay line (model.delay_samples = D samples, held in the
//      state) and u_{k-D} comes out; commands before t = 0 are those given to Reset();
//   4. the backend advances one sample with u_{k-D} (the Newtonian backend cuts it into
//      physics steps and applies the arm's effects and friction at each:
//      sim/newtonian_arm_backend.h).
// So a command sent at sample k acts over [t_{k+D}, t_{k+D+1}): q and qd sampled at
// k + D + 1 are the first that show it, on every backend.
//
// The model is fixed at construction; ArmSimulationState holds all that changes, and
// Save()/Restore() make a run repeatable from any sample, bit for bit.
//
//   ArmSimulation sim(model, MakeArmBackend("ode", model));
//   sim.Reset(q0, qd0);
//   ArmTrajectory run = sim.Run(2000, [&](double t, const Eigen::VectorXd& q,
//                                         const Eigen::VectorXd& qd) { return tau; });
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/delay_line.h"
#include "robots/arm/arm_model.h"
#include "sim/arm_backend.h"

namespace twinsim {

struct ArmSimulationOptions {
  double max_speed = 1e3;  // rad/s or m/s: a joint faster than this has run away

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// Joint torques (N·m or N, dof) to send at time t (s), given the joint positions
// (rad or m) and velocities sampled then.
using ArmController =
    std::function<Eigen::VectorXd(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd)>;

// What happened in one sample.
struct ArmSample {
  double t = 0;             // s
  Eigen::VectorXd q, qd;    // dof, sampled at t
  Eigen::VectorXd command;  // dof, N·m or N: sent by the controller at t
  Eigen::VectorXd applied;  // dof, N·m or N: the drive torque over [t, t + Ts), averaged
                            // (after the delays, saturation and offset; before friction
                            // and before a flexible joint's motor and spring)
};

// A run, one row per sample.
struct ArmTrajectory {
  std::string backend;
  double sample_time = 0;   // s
  Eigen::VectorXd t;        // N, s
  Eigen::MatrixXd q, qd;    // N x dof
  Eigen::MatrixXd command;  // N x dof
  Eigen::MatrixXd applied;  // N x dof
};

struct ArmSimulationState {
  std::int64_t sample = 0;
  DelayLine<Eigen::VectorXd> commands_in_flight;  // model.delay_samples long
  ArmBackendState backend;
  // The state of the last sample that passed the divergence check (its message gives it).
  double last_good_t = 0;
  Eigen::VectorXd last_good_q, last_good_qd;
};

class ArmSimulation {
 public:
  // Takes a backend built for `model` (MakeArmBackend) and resets it to q = 0 at rest.
  // Throws std::invalid_argument for a backend of another arm, and InputError for bad
  // options or a model that does not Validate().
  ArmSimulation(const ArmModel& model, std::unique_ptr<ArmBackend> backend, const ArmSimulationOptions& options = {});

  // The plant simulated: the model given, its payload lumped into the last link.
  const ArmModel& model() const { return model_; }
  const ArmBackend& backend() const { return *backend_; }
  int physics_substeps() const { return backend_->physics_substeps(); }
  std::int64_t sample() const { return state_.sample; }
  double time() const { return static_cast<double>(state_.sample) * model_.sample_time; }

  // Restarts at t = 0 from (q, qd) (flexible joints' motors at the links' positions)
  // with `tau_before` (dof; empty = zero) as every command sent before t = 0.
  // Throws std::invalid_argument for wrong sizes or non-finite values.
  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before = {});

  // Runs one sample under `controller`. Throws CheckFailed when the arm's state is not
  // finite or runs away, or the controller sends a non-finite torque (naming the joint,
  // time and value), and std::invalid_argument when it sends the wrong number.
  ArmSample Step(const ArmController& controller);

  // Runs `samples` samples; `progress(done, total)` is called now and then.
  ArmTrajectory Run(int samples, const ArmController& controller,
                    const std::function<void(int, int)>& progress = {});

  ArmSimulationState Save() const;
  // Throws std::invalid_argument for a state of another arm or backend.
  void Restore(const ArmSimulationState& state);

 private:
  void CheckState();
  // Step into *out, whose vectors are reused (Run steps into one sample throughout).
  void StepInto(const ArmController& controller, ArmSample* out);

  ArmModel model_;  // the plant: payload lumped into the last link
  std::unique_ptr<ArmBackend> backend_;
  ArmSimulationOptions options_;
  ArmSimulationState state_;
  Eigen::VectorXd delayed_;  // dof: the command leaving the delay line (scratch, not state)
};

}  // namespace twinsim
