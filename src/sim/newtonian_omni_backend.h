// A "Newtonian" backend: a physics engine (ODE, Bullet or the analytic model) with the
// robot's on-board controller, encoders and motors on top.
//
// Within a frame the loop runs `physics_substeps` engine steps; the controller ticks
// every round(physics rate / controller rate) steps on quantised encoder readings, and
// the motor model limits the torque on each step. The engine only ever sees net wheel
// torques, so all engines are driven identically.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "robots/omni/omni_kinematics.h"
#include "sim/omni_backend.h"

namespace twinsim {

class NewtonianOmniBackend final : public OmniBackend {
 public:
  NewtonianOmniBackend(std::unique_ptr<OmniEngine> engine, const std::vector<OmniModel>& robots,
                       const FrameTiming& timing);

  std::string name() const override { return engine_->name(); }
  int num_robots() const override { return static_cast<int>(robots_.size()); }
  const FrameTiming& timing() const override { return timing_; }

  void Reset(int robot, const Pose2& pose, const Twist2& velocity) override;
  void MoveBody(int robot, const Pose2& pose) override;
  bool has_velocity_state() const override { return true; }
  void SetVelocity(int robot, const Twist2& velocity) override;
  void StepFrame(const std::vector<Twist2>& commands) override;
  Pose2 pose(int robot) const override;
  Twist2 velocity(int robot) const override;
  GripCheck grip() const override { return engine_->grip(); }
  OmniBackendState Save() const override;
  void Restore(const OmniBackendState& state) override;

  OmniEngine& engine() { return *engine_; }
  // The controller's state of robot i (for tests and diagnostics).
  const OnboardControllerState& controller(int robot) const { return robots_.at(robot).state.controller; }

 private:
  struct Robot {
    OmniModel model;
    OmniKinematics kin;
    int ticks_per_control = 1;  // physics steps per controller tick
    bool effects_on = false;    // the model has effects (omni_effects.h)
    OmniRobotState state;       // controller part; body part refreshed on Save()
    Eigen::VectorXd speeds;     // n, scratch: wheel speeds read this step
    Eigen::VectorXd seen;       // n, scratch: wheel speeds as the firmware believes them
    Eigen::VectorXd net;        // n, scratch: net wheel torques
    int index = 0;              // in the engine
    // motor_lag's share of the way to its target per physics step, 1 - exp(-dt / tau),
    // per axis, accelerating and braking; 0 where the time constant is 0 (no lag).
    std::array<double, 3> lag_share{}, lag_share_braking{};
    double series_share = 0;  // the same for motor_lag's lag in series (`series`)
  };

  // The command the firmware acts on at this physics step, after time_delay,
  // velocity_saturation, motor_lag (its braking and field frame included) and
  // traction_limit.
  Twist2 EffectiveCommand(Robot& r, const Twist2& received, bool new_frame, double dt);
  // `c` through motor_lag: its lag in series, then each axis's (braking and field frame
  // included); the lags' states move on by the physics step dt.
  Twist2 Lagged(Robot& r, Twist2 c, double dt);
  // The encoder speeds the firmware believes (velocity_scale, rotation_drift).
  void SeenWheelSpeeds(Robot& r, Eigen::VectorXd* speeds) const;
  // Net wheel torques after traction_limit's force cap and the motors.
  void NetTorques(Robot& r);

  std::unique_ptr<OmniEngine> engine_;
  std::vector<Robot> robots_;
  FrameTiming timing_;
};

// The Newtonian backend of `robots` on engine `engine` (analytic, ode, bullet:
// MakeOmniEngine, which throws InputError for another or one not built in), in `field`.
std::unique_ptr<NewtonianOmniBackend> MakeNewtonianOmniBackend(const std::string& engine,
                                                               const std::vector<OmniModel>& robots,
                                                               const FieldModel& field, const FrameTiming& timing);

}  // namespace twinsim
