// The Newtonian arm backend: an ArmEngine (analytic, ode or bullet: bodies and joints
// only) with the arm's friction and effects on top, as NewtonianOmniBackend puts the omni
// robot's firmware, motors and effects on an OmniEngine.
//
// Each sample of Ts (the model's sample_time) is cut into `physics_substeps` physics
// steps of h = Ts / substeps. At every physics step, per joint: time_delay,
// torque_saturation and torque_offset shape the received command into the drive torque;
// joint_flexibility passes it through the motor inertia and spring (explicitly, or by
// the trapezoidal rule solved with the friction: ArmModel::flexibility_integrator);
// friction (the joint's nominal viscous and Coulomb friction plus the friction effects)
// is solved at velocity level, so a joint sticks exactly and viscous friction is
// trapezoidal (a pre-sliding joint's bristles, stribeck_friction with sigma0, are solved
// with it and integrated exactly over the step: it deflects before it slides instead of
// sticking); the engine steps h, its first stage from the solve's M where there was
// one (ArmEngine::StepFromAcceleration). The payload is in the bodies the engine is
// built with (ArmPlantModel).
//
//   ArmSimulation sim(model, MakeNewtonianArmBackend("ode", model));
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "engines/arm_engine.h"
#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_model.h"
#include "sim/arm_backend.h"

namespace twinsim {

class NewtonianArmBackend final : public ArmBackend {
 public:
  // Takes an engine built for ArmPlantModel(model). `physics_substeps`: physics steps per
  // sample, 0 = automatic: 1, or as many as a stiff joint_flexibility needs
  // (explicit: h sqrt(k / J_eff) <= 0.1 and h d / J_eff <= 0.5; trapezoidal:
  // h sqrt(k / J_eff) <= 0.34; pre-sliding bristles: h sqrt(sigma0 / J_l) <= 0.5, at
  // most 64 steps; the link's inertia taken at q = 0 with the other joints free). Throws
  // std::invalid_argument for an engine of another arm, InputError for a model that does
  // not Validate() or substeps out of [0, 100000].
  NewtonianArmBackend(const ArmModel& model, std::unique_ptr<ArmEngine> engine, int physics_substeps = 0);

  std::string name() const override { return engine_->name(); }
  int dof() const override { return model_.dof(); }
  int physics_substeps() const override { return substeps_; }
  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before) override;
  void Step(const Eigen::VectorXd& command, Eigen::VectorXd* applied) override;
  const Eigen::VectorXd& q() const override { return engine_->q(); }
  const Eigen::VectorXd& qd() const override { return engine_->qd(); }
  ArmBackendState Save() const override;
  void Restore(const ArmBackendState& state) override;

 private:
  // The drive torque of every joint over physics step `step` (time_delay, saturation,
  // offset), from the commands received.
  void DriveTorques(std::int64_t step, Eigen::VectorXd* drive) const;
  // Friction torques (opposing positive motion) for one physics step of h seconds
  // with the other joint torques `tau` (flexible joints' springs not in it), solved at
  // velocity level, and with them the mean spring torques of the trapezoidal flexible
  // joints driven by `drive` (zero elsewhere). Returns true when it solved (some joint
  // has friction or a trapezoidal spring), with the joint accelerations at the step's
  // start under tau + spring - friction in scratch_.start_accel, from the same M: the
  // engine's first stage (ArmEngine::StepFromAcceleration).
  // A LuGre joint j's bristles over a physics step of h from position q and velocity qd,
  // into scratch_.
  void PrepareBristles(int j, double q, double qd, double h);
  // Its friction torque for a free end velocity v and response w (the joint's
  // (h M^-1)_jj), from velocity qd: A + B v_end solved with v_end = v - w f, or for a
  // Maxwell-slip element whose force would exceed its dry level, that level (then
  // scratch_.slid).
  double BristleFriction(int j, double v, double w, double qd, double h);
  bool SolveJointTorques(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau,
                         const Eigen::VectorXd& drive, double h, Eigen::VectorXd* friction, Eigen::VectorXd* spring);

  // Work space of Step and SolveJointTorques, kept so that a step allocates nothing; its
  // content between steps means nothing (not state: Save and Restore ignore it).
  struct Scratch {
    Eigen::VectorXd drive, link, friction;  // dof: a physics step's torques
    Eigen::VectorXd bias, free_end;         // dof: the friction solve's free motion
    Eigen::VectorXd free_accel;             // dof: M^-1 (tau - bias)
    Eigen::VectorXd start_accel;            // dof: M^-1 (tau - friction - bias)
    Eigen::MatrixXd mass, mobility;         // dof x dof: M and M^-1
    Eigen::MatrixXd response;               // dof x dof: h M^-1
    Eigen::MatrixXd factor;                 // dof x dof: M's Cholesky factor, inverted
    Eigen::VectorXd delayed;                // dof: a command's storage, recycled
    Eigen::VectorXd spring;                 // dof: trapezoidal flexible joints' mean spring torque
    Eigen::VectorXd w_inverse;              // dof: 1 / (h M^-1)_jj of the friction joints
    Eigen::VectorXd damping_inverse;        // dof: 1 / (1 + (h M^-1)_jj b_j / 2)
    std::vector<ArmBristleStep> bristle_steps;  // dof: LuGre joints' bristles over the step
    Eigen::VectorXd bristle_torque, bristle_gain;  // dof: their friction A + B v_end
    std::vector<ArmSlipLevels> slip_levels;  // dof: Maxwell-slip elements' levels over the step
    std::vector<bool> slid;          // dof: the element slipped in the last solve
    Eigen::VectorXd slid_deflection;  // dof: its deflection then
  };

  ArmModel model_;  // the plant: payload lumped into the last link
  std::unique_ptr<ArmEngine> engine_;
  int substeps_ = 1;
  std::vector<JointEffects> effects_;  // dof
  std::vector<int> friction_joints_;   // joints with any friction
  std::vector<int> presliding_joints_;  // joints with LuGre friction (bristles)
  std::vector<int> trapezoidal_joints_;  // flexible joints stepped by the trapezoidal rule
  std::vector<int> position_torque_joints_;  // joints with a position_torque
  std::vector<double> delay_steps_;    // per joint, time_delay in physics steps
  double max_delay_steps_ = 0;
  bool flexible_ = false;
  ArmBackendState state_;  // all but the engine's part
  Scratch scratch_;
};

// A Newtonian backend over the engine called `engine` ("analytic", "ode", "bullet"),
// built for ArmPlantModel(model). Throws as MakeArmEngine and the constructor do.
std::unique_ptr<ArmBackend> MakeNewtonianArmBackend(const std::string& engine, const ArmModel& model,
                                                    int physics_substeps = 0, const ArmEngineOptions& options = {});

}  // namespace twinsim
