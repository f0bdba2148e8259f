// Arm logs made by MuJoCo (Debian's libmujoco-dev): an engine written elsewhere, with its
// own inverse dynamics, integrator and joint damping, recorded with noise models the
// project's own plants (diagnosis_plants.h) do not use. The diagnosis gets the nominal
// model and the log read back from its CSV text, as a user's file would be read; what
// the plant hides is known to the test alone.
//
// Built where MuJoCo was found at configure time (TWINSIM_HAVE_MUJOCO). Elsewhere
// MujocoAvailable() is false and RecordMujocoArm throws: the tests that need it skip.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>

#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {
namespace testing {

bool MujocoAvailable();

// URDF of `model` (its joint table as it is, inertials about the centre of mass),
// readable by urdfdom and by MuJoCo: the same text loads on both sides.
std::string ArmUrdf(const ArmModel& model);

// A torque acting on the joints beside the motors' (rows: joints), never logged: a hidden
// effect (a spring, cogging). Called once per sample with the time and the exact motion.
using HiddenArmTorque = std::function<Eigen::VectorXd(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& qd)>;

// `torque(q, qd)` of one joint's own motion on `joint` (0-based), nothing on the others.
HiddenArmTorque HiddenOnJoint(int joint, std::function<double(double q, double qd)> torque);

struct ForeignArmRecording {
  double seconds = 30;
  // false: the motion is the excitation exactly and the logged torque is MuJoCo's
  // inverse dynamics of it plus friction, less the hidden torque, sent the model's
  // delay early. true: MuJoCo integrates the plant (RK4, the model's sample time) under a
  // PD controller with feedforward from its own inverse dynamics of the reference; the
  // logged torque is the command.
  bool closed_loop = false;
  double quantum = 2e-5;           // rad, encoder resolution (q quantised)
  double noise_share = 0.02;       // white torque noise: this share of each joint's mean |torque|
  double proportional_noise = 0;   // and this share of the torque itself, row by row
  double noise_correlation = 0;    // s: the white share made coloured (first order, this correlation time); 0: white
  double cutoff_hz = 10;           // the reader's cut-off for the derived qd, qdd
  HiddenArmTorque hidden;          // empty: a clean plant
};

// One log of `plant` under a random Fourier excitation (5 harmonics of 0.1 Hz, each joint
// sweeping a drawn 10 to 70 % of its range, at most 2.5 rad/s), seeded.
ArmLog RecordMujocoArm(const ArmModel& plant, std::uint64_t seed, const ForeignArmRecording& how = {});

}  // namespace testing
}  // namespace twinsim
