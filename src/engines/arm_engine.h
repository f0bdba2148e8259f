// An engine for a fixed-base serial arm: it integrates the rigid-body dynamics of the
// arm's links under joint torques, and knows bodies and joints only: no friction, no
// limits, no collisions, no delays. The Newtonian arm backend (sim/newtonian_arm_backend.h)
// puts the arm's friction and effects on top of it, so all engines feel exactly the same
// torques at the same times, as OmniEngine does for the omni robot.
//
// Three engines implement it: "analytic" (the model's own forward dynamics,
// robots/arm/arm_dynamics.h, by RK4), "ode" (one ODE body per link on hinges and
// sliders, maximal coordinates) and "bullet" (a Bullet btMultiBody, reduced
// coordinates). MakeArmEngine() picks one by name.
//
//   std::unique_ptr<ArmEngine> e = MakeArmEngine("bullet", ArmPlantModel(model));
//   e->Reset(q0, qd0);
//   e->Step(tau, 0.001);          // 1 ms with tau held
//   ArmEngineState s = e->Save();  // ... e->Restore(s) puts it back exactly
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

// Everything that changes inside an engine: enough to put it back bit for bit.
struct ArmEngineState {
  Eigen::VectorXd q;            // dof, rad or m
  Eigen::VectorXd qd;           // dof, rad/s or m/s
  std::vector<double> exact;    // the engine's own numbers (body poses...), opaque
};

struct ArmEngineOptions {
  // s: the longest internal integration step; a Step(dt) is cut into
  // ceil(dt / max_step) equal steps. 0 = the engine's default (DefaultArmMaxStep).
  double max_step = 0;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

class ArmEngine {
 public:
  virtual ~ArmEngine() = default;
  virtual std::string name() const = 0;
  virtual int dof() const = 0;

  // Puts the arm at joint positions q moving at qd, as if freshly built there.
  // Throws std::invalid_argument for vectors of the wrong size or non-finite values.
  virtual void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) = 0;

  // Advances dt seconds with joint torques `tau` (N·m or N, dof) held constant.
  // Throws std::invalid_argument for a wrong size or dt <= 0.
  virtual void Step(const Eigen::VectorXd& tau, double dt) = 0;

  // As Step, for a caller that already has `qdd` (dof): the joint accelerations the arm
  // has now under `tau`, i.e. ForwardDynamics(plant, q(), qd(), tau, friction off) up to
  // round-off (the Newtonian backend's friction solve has them from its M and bias). An
  // engine that integrates the joint-space equations (analytic) takes them as its first
  // stage instead of computing them again; the others ignore them. Throws as Step.
  virtual void StepFromAcceleration(const Eigen::VectorXd& tau, double dt, const Eigen::VectorXd& qdd) {
    static_cast<void>(qdd);
    Step(tau, dt);
  }

  virtual const Eigen::VectorXd& q() const = 0;   // dof, rad or m
  virtual const Eigen::VectorXd& qd() const = 0;  // dof, rad/s or m/s

  // Saves and restores everything that changes: restoring a saved state and stepping
  // gives bit for bit what stepping from where it was saved gave. Restore throws
  // std::invalid_argument for a state of another arm or engine.
  virtual ArmEngineState Save() const = 0;
  virtual void Restore(const ArmEngineState& state) = 0;
};

// The internal step an engine uses when ArmEngineOptions::max_step is 0 (s).
double DefaultArmMaxStep(const std::string& backend);

// Builds the engine called `name` ("analytic", "ode", "bullet") for `model`'s plant
// (ArmPlantModel: its payload lumped into the last link), at q = 0 and at rest.
// Throws InputError for an unknown or uncompiled backend, bad options or a model that
// does not Validate().
std::unique_ptr<ArmEngine> MakeArmEngine(const std::string& name, const ArmModel& model,
                                         const ArmEngineOptions& options = {});

// The arm engines compiled into this build.
std::vector<std::string> AvailableArmEngines();

// For the implementations: internal steps for one Step of dt seconds with steps of at
// most max_step (at least 1).
int ArmSubsteps(double dt, double max_step);
// Throws std::invalid_argument unless q and qd have `dof` finite entries.
void CheckArmState(const std::string& backend, int dof, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
// Throws std::invalid_argument unless tau has `dof` entries and dt > 0 is finite.
void CheckArmStep(const std::string& backend, int dof, const Eigen::VectorXd& tau, double dt);

}  // namespace twinsim
