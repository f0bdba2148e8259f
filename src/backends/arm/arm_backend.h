// A backend for a fixed-base serial arm: it integrates the rigid-body dynamics
// of the arm's links under joint torques that the simulation loop (core/arm_simulation.h)
// has already delayed and passed through the arm's effects.
//
// Three backends implement it: "analytic" (the model's own forward dynamics,
// robots/arm/arm_dynamics.h, by RK4), "ode" (one ODE body per link on hinges and
// sliders, maximal coordinates) and "bullet" (a Bullet btMultiBody, reduced
// coordinates). A backend knows bodies and joints only: no friction, no limits, no
// collisions; friction, delays and every other effect act above it, so all backends
// feel exactly the same torques at the same times. MakeArmBackend() picks one by name.
//
// The "learned" backend (backends/learned/learned_arm_backend.h) is different: it steps
// a predictor learned from a real arm's logs, which has learned that arm's friction and
// effects with its bodies. It says so with includes_plant_effects(), and the simulation
// loop then hands it the delayed command as it is (no effects, no friction) and steps it
// exactly one sample at a time.
//
//   std::unique_ptr<ArmBackend> b = MakeArmBackend("bullet", model);
//   b->Reset(q0, qd0);
//   b->Step(tau, 0.001);          // 1 ms with tau held
//   ArmBackendState s = b->Save();  // ... b->Restore(s) puts it back exactly
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

// Everything that changes inside a backend: enough to put it back bit for bit.
struct ArmBackendState {
  Eigen::VectorXd q;            // dof, rad or m
  Eigen::VectorXd qd;           // dof, rad/s or m/s
  std::vector<double> exact;    // the engine's own numbers (body poses...), opaque
};

struct ArmBackendOptions {
  // s: the longest internal integration step; a Step(dt) is cut into
  // ceil(dt / max_step) equal steps. 0 = the backend's default (DefaultArmMaxStep).
  double max_step = 0;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

class ArmBackend {
 public:
  virtual ~ArmBackend() = default;
  virtual std::string name() const = 0;
  virtual int dof() const = 0;

  // True when the backend's dynamics already contain the arm's friction and effects
  // (a learned model of the real arm): the loop then adds none of them and steps it one
  // whole sample at a time. False for the physics engines (bodies and joints only).
  virtual bool includes_plant_effects() const { return false; }

  // Puts the arm at joint positions q moving at qd, as if freshly built there.
  // Throws std::invalid_argument for vectors of the wrong size or non-finite values.
  virtual void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) = 0;

  // Advances dt seconds with joint torques `tau` (N·m or N, dof) held constant.
  // Throws std::invalid_argument for a wrong size or dt <= 0.
  virtual void Step(const Eigen::VectorXd& tau, double dt) = 0;

  virtual const Eigen::VectorXd& q() const = 0;   // dof, rad or m
  virtual const Eigen::VectorXd& qd() const = 0;  // dof, rad/s or m/s

  // Saves and restores everything that changes: restoring a saved state and stepping
  // gives bit for bit what stepping from where it was saved gave. Restore throws
  // std::invalid_argument for a state of another arm or backend.
  virtual ArmBackendState Save() const = 0;
  virtual void Restore(const ArmBackendState& state) = 0;
};

// The internal step a backend uses when ArmBackendOptions::max_step is 0 (s).
double DefaultArmMaxStep(const std::string& backend);

// Builds the backend called `name` ("analytic", "ode", "bullet") for `model`'s plant
// (ArmPlantModel: its payload lumped into the last link), at q = 0 and at rest.
// Throws InputError for an unknown or uncompiled backend or bad options, and
// std::invalid_argument for a model that does not Validate().
std::unique_ptr<ArmBackend> MakeArmBackend(const std::string& name, const ArmModel& model,
                                           const ArmBackendOptions& options = {});

// The arm backends compiled into this build.
std::vector<std::string> AvailableArmBackends();

// For the implementations: internal steps for one Step of dt seconds with steps of at
// most max_step (at least 1).
int ArmSubsteps(double dt, double max_step);
// Throws std::invalid_argument unless q and qd have `dof` finite entries.
void CheckArmState(const std::string& backend, int dof, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
// Throws std::invalid_argument unless tau has `dof` entries and dt > 0 is finite.
void CheckArmStep(const std::string& backend, int dof, const Eigen::VectorXd& tau, double dt);

}  // namespace twinsim
