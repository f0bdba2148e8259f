// What the arm loop (sim/arm_simulation.h) steps, one sample at a time, with commands it
// has already delayed: the arm's plant. The same seam as OmniBackend for the omni robot.
//
// Two kinds implement it:
//   - the Newtonian backend (sim/newtonian_arm_backend.h): an ArmEngine (analytic, ode,
//     bullet: bodies and joints only) with the arm's friction and effects on top
//     (time_delay, torque_saturation, torque_offset, joint_flexibility, the friction
//     effects), cut into physics steps;
//   - the learned backend (backends/learned/learned_arm_backend.h): a predictor learned
//     from the real arm's logs, which has learned that arm's friction and effects with
//     its bodies, so nothing is added on top and it steps whole samples.
// MakeArmBackend() (backends/arm_backend_factory.h) builds any of them by name.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "engines/arm_engine.h"

namespace twinsim {

// Everything that changes inside an arm backend: enough to put it back bit for bit.
struct ArmBackendState {
  std::int64_t sample = 0;  // samples stepped since Reset
  // time_delay: the commands received, each with the physics step it arrived at, oldest
  // first; before the first one, `held_before` (dof).
  std::vector<std::pair<std::int64_t, Eigen::VectorXd>> arrived;
  Eigen::VectorXd held_before;
  // joint_flexibility: the motor side of each joint (rad, rad/s); rigid joints unused.
  Eigen::VectorXd motor_q, motor_qd;
  // LuGre friction (stribeck_friction with sigma0): each joint's bristle deflection z
  // (rad or m); other joints unused.
  Eigen::VectorXd bristle;
  ArmEngineState engine;  // the engine's bodies, or the learned backend's window
};

class ArmBackend {
 public:
  virtual ~ArmBackend() = default;
  virtual std::string name() const = 0;
  virtual int dof() const = 0;
  // Physics steps per sample (1 for the learned backend).
  virtual int physics_substeps() const = 0;

  // Restarts at (q, qd) (flexible joints' motors at the links' positions), with
  // `tau_before` (dof) as every command received before t = 0. Throws
  // std::invalid_argument for wrong sizes or non-finite values.
  virtual void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before) = 0;

  // Advances one sample of the model's sample time with `command` (N·m or N, dof), the
  // command the loop's delay line let through now. Writes into *applied (dof) the drive
  // torque over the sample, averaged: after time_delay, saturation and offset, before
  // friction and before a flexible joint's motor and spring (the command itself for the
  // learned backend).
  virtual void Step(const Eigen::VectorXd& command, Eigen::VectorXd* applied) = 0;

  virtual const Eigen::VectorXd& q() const = 0;   // dof, rad or m
  virtual const Eigen::VectorXd& qd() const = 0;  // dof, rad/s or m/s

  // Saves and restores everything that changes. Restore throws std::invalid_argument
  // for a state of another arm or backend.
  virtual ArmBackendState Save() const = 0;
  virtual void Restore(const ArmBackendState& state) = 0;
};

}  // namespace twinsim
