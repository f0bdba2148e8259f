// A linear drive made elsewhere, as the EMPS benchmark's (Janot, Gautier and Brunot,
// "Data set and reference models of EMPS", 2019) describes it: a prismatic axis (a cart
// of 95.1 kg on a ball screw) under a cascade of a proportional position loop and a
// proportional velocity loop, sampled at 1 kHz, logged as the encoder's position and the
// force the drive received. MuJoCo integrates it (its own integrator, joint damping and
// friction loss: a dry friction that holds the cart at rest, where the project's model
// has sign(q̇)); the logged force is the controller's output through a quantised
// converter, the encoder quantised at a micrometre. The held-out run adds force pulses
// to the controller's output, as the benchmark's test run does.
//
// The parameters are Janot's published ones for the real drive; what a fit should find
// is in EmpsLikeTruth. The identification under test gets the log's CSV text alone.
//
// Built where MuJoCo was found at configure time (TWINSIM_HAVE_MUJOCO); elsewhere
// RecordEmpsLike throws and the tests that need it skip (MujocoAvailable()).
#pragma once

#include <cstdint>
#include <string>

namespace twinsim {

struct ArmLog;
struct ArmModel;

namespace testing {

struct EmpsLikeTruth {
  double mass = 95.1089;     // kg
  double viscous = 203.5034;  // N s/m
  double coulomb = 20.3935;   // N (MuJoCo's friction loss: it also holds the cart at rest)
  double offset = -3.1648;    // N, a constant force on the cart (the drive's offset)
  // A friction loss that varies along the travel (a screw tighter at one end): MuJoCo's
  // friction loss set before each step to coulomb (1 + coulomb_wave cos(pi (q - 0.02 m)
  // / 0.2 m)), so coulomb (1 + wave) at the travel's start, coulomb (1 - wave) at its
  // end. 0 = the same everywhere. Not with presliding_stiffness.
  double coulomb_wave = 0;
  // A force along the travel that does not depend on the motion (a cable chain pulling
  // the cart; position_torque's kind): cable cos(2 pi (q - 0.02 m) / 0.2 m) N on the
  // cart, +cable at both ends of the travel and -cable in its middle. 0 = none.
  double cable = 0;
  // Pre-sliding, as a Maxwell-slip element: with a stiffness (N/m) the dry friction acts
  // on a slider of `slider_mass` (kg, part of `mass`) joined to the cart by that spring,
  // damped at `presliding_damping_ratio` of critical against the cart; MuJoCo steps it at
  // 0.1 ms. 0 = the friction on the cart itself, as the benchmark's model has it.
  double presliding_stiffness = 0;
  double slider_mass = 5;
  double presliding_damping_ratio = 0.5;
};

struct EmpsLikeRecording {
  double seconds = 24.8;
  bool pulses = false;         // the held-out run: force pulses added to the controller's output
  double quantum = 1e-6;       // m, the encoder's resolution
  double force_noise = 0.3;    // N, white noise on the logged force
  EmpsLikeTruth truth;
};

// The log's CSV text (t,q1,tau1) of one run, the reference drawn from `seed`: moves
// between 0.02 and 0.22 m at 0.05 to 0.35 m/s with dwells between them.
std::string RecordEmpsLike(std::uint64_t seed, const EmpsLikeRecording& how = {});

// The a-priori model a user would write for it: a 90 kg cart on a prismatic joint along
// x, no friction (YAML text).

// The friction loss of `truth` at cart position q (N): its coulomb_wave along the travel.
double EmpsLikeFrictionLoss(const EmpsLikeTruth& truth, double q);
// The cable's force of `truth` on the cart at position q (N).
double EmpsLikeCableForce(const EmpsLikeTruth& truth, double q);
std::string EmpsLikeNominalYaml();

// The benchmark's score of a one-joint model on a log: its free run from the log's first
// state, driven by the logged force, as a fit in % (100 (1 - ||q - q_sim|| / ||q - mean q||)).
double FreeRunFit(const ArmModel& model, const ArmLog& log);

}  // namespace testing
}  // namespace twinsim
