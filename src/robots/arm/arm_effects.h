// The arm effect vocabulary of CONTRACT.md: behaviour a real arm has and the rigid-body
// model with its nominal friction lacks. A model file switches effects on with an
// `effects:` list (docs/arm_backends.md), the diagnosis workflow names and adds them,
// and the arm simulation loop (sim/arm_simulation.h) makes them act, above the physics
// engines, so that ODE, Bullet and the analytic model all feel them alike.
//
// Per joint j (the command u is what the controller sent, after the model's delay):
//   time_delay          the joint receives u(t - delay)
//   torque_saturation   it receives clip(u, -limit, +limit)
//   torque_offset       plus a constant tau0
//   position_torque     plus p(q), a torque that varies along the joint's travel (a
//                       cable or hose pulling, a spring, a tilted axis, a motor's
//                       cogging at a coarse pitch): through the levels p1..pK at K
//                       evenly spaced positions from `from` to `to` as position_friction's
//                       c(q), but acting whether or not the joint moves
//   joint_flexibility   that torque drives a motor inertia J_m joined to the link by a
//                       spring k with damping d: J_m thm'' = u - tau_s,
//                       tau_s = k (thm - q) + d (thm' - qd) drives the link
//   viscous_friction    tau_f = b qd
//   coulomb_friction    tau_f = c_pos (qd > 0), -c_neg (qd < 0), sticking in between
//   position_friction   tau_f = c(q) sign(qd): a dry friction level that varies along the
//                       joint's travel (a ball screw or a gear tighter in some places),
//                       c(q) through the levels c1..cK at K evenly spaced positions from
//                       `from` to `to`, linear between them, c1 before `from` and cK
//                       beyond `to`; it adds to the Coulomb levels and, like them, holds
//                       a joint at rest and sets where bristles slip. A level may be
//                       negative where the joint's Coulomb friction covers it: the total
//                       must not be (ArmModel::Validate)
//   stribeck_friction   tau_f = (c + (s - c) exp(-(qd/vs)^2)) sign(qd), breaking away at s;
//                       with sigma0 > 0 the LuGre model whose steady state that is
//                       (Canudas de Wit et al. 1995): the joint's whole dry friction
//                       g(qd) (nominal and effect Coulomb levels plus this one) acts
//                       through bristles of deflection z,
//                         z' = qd - alpha sigma0 |qd| z / g(qd),
//                         tau_f = sigma0 z + sigma1 z' + (viscous) qd,
//                       so below break-away the joint moves by about tau / sigma0
//                       (pre-sliding) instead of standing rigidly still. LuGre has
//                       alpha = 1: its bristles creep under any load, and sigma1 z'
//                       adds to g. With `maxwell: 1` they are a Maxwell-slip element
//                       instead (Lampaert et al. 2003, one element): alpha = 0, a
//                       damped spring that slips where its force sigma0 z + sigma1 z'
//                       would exceed g, so the dry friction never exceeds g
// and for the arm (joint: null):
//   payload             a point mass m at (x, y, z) in the last link's frame (default its
//                       origin; the struct's frame, see arm_model.h: on the last joint's
//                       axis for a DH table, so a mass at a DH arm's tool needs x = a_n)
// Friction torques oppose the motion and add to the joints' nominal viscous and Coulomb
// friction (ArmJoint::viscous, ::coulomb).
//
// Use: ArmModel::effects holds them; AddArmEffect() adds one by name and parameters
// (as report.json lists them), ListArmEffects() gives them back in that form.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace twinsim {

struct ArmModel;
class ErrorList;

// The most knots of a profile along a joint's travel (position_friction's levels,
// position_torque's): a fixed array, so that JointEffects copies without allocating (it
// is read for every joint of every sample of a fit).
inline constexpr int kMaxProfileKnots = 12;

// Where q lies among `knots` knots evenly spaced from `from` to `to`: 0 at the first,
// knots - 1 at the last, held within them.
inline double KnotCoordinate(double from, double to, int knots, double q) {
  return std::clamp((q - from) / (to - from), 0.0, 1.0) * (knots - 1);
}

// The weight of knot k (0-based) of `knots` evenly spaced from `from` to `to` at
// position q: the hat that is 1 at the knot and 0 at its neighbours, linear between,
// with q held within [from, to] (the end knots' weights 1 beyond them). The weights sum
// to 1 at every q: a profile's value is sum_k level_k KnotWeight(...).
inline double KnotWeight(double from, double to, int knots, int k, double q) {
  return std::max(0.0, 1 - std::abs(KnotCoordinate(from, to, knots, q) - k));
}

// A quantity that varies along a joint's travel: levels at `knots` positions evenly
// spaced from `from` to `to`, linear between them, the first level before `from` and
// the last beyond `to` (position_friction's c(q), position_torque's p(q)).
struct KnotProfile {
  int knots = 0;  // 0 = off, else 2..kMaxProfileKnots
  double from = 0;  // rad or m: the first knot
  double to = 0;    // rad or m: the last (> from)
  std::array<double, kMaxProfileKnots> levels{};

  bool on() const { return knots > 0; }
  // The profile's value at position q (0 when off).
  double At(double q) const {
    if (knots == 0) return 0;
    const double u = KnotCoordinate(from, to, knots, q);
    const int k = std::min(static_cast<int>(u), knots - 2);
    const double a = u - k;
    const auto i = static_cast<std::size_t>(k);
    return (1 - a) * levels[i] + a * levels[i + 1];
  }
};

// A profile's key of level k (0-based): `letter` then k + 1 (position_friction's "c1",
// "c2", ..., position_torque's "p1", ...).
std::string ProfileLevelKey(char letter, int k);
// How many levels `parameters` holds: letter1, letter2, ... up to the first missing one.
int ProfileLevelCount(char letter, const std::map<std::string, double>& parameters);

// The effects of one joint; all off by default. Units: N·m for revolute joints, N for
// prismatic ones (and rad or m for positions accordingly).
struct JointEffects {
  double viscous = 0;            // N·m·s/rad: viscous_friction b
  double coulomb_positive = 0;   // N·m: coulomb_friction while qd > 0 (c_pos)
  double coulomb_negative = 0;   // N·m: coulomb_friction while qd < 0 (c_neg), a magnitude
  double stribeck_coulomb = 0;   // N·m: stribeck_friction c, the sliding level
  double stribeck_static = 0;    // N·m: stribeck_friction s > c, the break-away level
  double stribeck_velocity = 0;  // rad/s: stribeck_friction vs; 0 = off
  double bristle_stiffness = 0;  // N·m/rad: stribeck_friction sigma0 (LuGre); 0 = no pre-sliding
  double bristle_damping = 0;    // N·m·s/rad: stribeck_friction sigma1 (LuGre)
  bool bristle_slip = false;      // stribeck_friction maxwell: 1: a Maxwell-slip element, not LuGre
  KnotProfile friction_profile;   // position_friction: c1..cK, N·m (the joint's total level >= 0)
  double torque_offset = 0;      // N·m: torque_offset tau0
  KnotProfile torque_profile;     // position_torque: p1..pK, N·m
  double saturation = 0;         // N·m: torque_saturation limit; 0 = off
  double time_delay = 0;         // s: time_delay delay
  double stiffness = 0;          // N·m/rad: joint_flexibility k; 0 = rigid
  double flex_damping = 0;       // N·m·s/rad: joint_flexibility damping
  double motor_inertia = 0;      // kg m^2: joint_flexibility motor_inertia, on the joint side

  bool stribeck() const { return stribeck_velocity > 0; }
  // LuGre: the dry friction acts through bristles (only with stribeck()).
  bool presliding() const { return bristle_stiffness > 0; }
  bool flexible() const { return stiffness > 0; }
  bool position_friction() const { return friction_profile.on(); }
  // position_friction's level c(q) at position q (0 when off).
  double PositionFrictionLevel(double q) const { return friction_profile.At(q); }
  // position_torque's p(q) at position q (0 when off): added to what the joint receives.
  double PositionTorque(double q) const { return torque_profile.At(q); }
  // The dry friction level (>= 0, no viscous part) of a joint whose nominal Coulomb level
  // is `coulomb`, at position q sliding at `speed` >= 0 in direction `dir` (+1 or -1; it
  // picks the Coulomb side where speed is 0, as a simulation asks either way at rest):
  // the Coulomb levels plus position_friction's and the Stribeck hump's.
  double SlidingLevel(double coulomb, double q, double speed, int dir) const {
    double level = coulomb + (dir > 0 ? coulomb_positive : coulomb_negative) + PositionFrictionLevel(q);
    if (stribeck()) {
      const double r = speed / stribeck_velocity;
      level += stribeck_coulomb + (stribeck_static - stribeck_coulomb) * std::exp(-r * r);
    }
    return level;
  }
  // True when the joint has some friction effect.
  bool friction() const {
    return viscous > 0 || coulomb_positive > 0 || coulomb_negative > 0 || stribeck() || position_friction();
  }
};

struct ArmEffects {
  std::vector<JointEffects> joints;  // one per joint once any joint effect is on, else empty
  double payload_mass = 0;           // kg; 0 = off
  Eigen::Vector3d payload_position = Eigen::Vector3d::Zero();  // m, in the last link's frame

  // The effects of joint j (0-based); all off when none were set. A copy, so that it
  // outlives a temporary model; inline, since it is read for every joint of every sample
  // of a fit and the compiler then copies only what the caller reads.
  JointEffects joint(int j) const {
    return j >= 0 && j < static_cast<int>(joints.size()) ? joints[static_cast<std::size_t>(j)] : JointEffects{};
  }
  bool any() const;
};

// How a joint's dry friction deflects before it slides (stribeck_friction's sigma0 and
// maxwell): not at all, LuGre's creeping bristles, or a Maxwell-slip element.
enum class ArmPresliding { kNone, kLugre, kMaxwellSlip };

// One effect as a model file and report.json name it.
struct ArmEffect {
  std::string name;                          // from ArmEffectNames()
  int joint = -1;                            // 0-based; -1 for payload (joint: null)
  std::map<std::string, double> parameters;  // keys as in the model file, SI units
};

// The arm effect vocabulary: the contract's names in its order, then twinsim's own
// (position_friction, position_torque).
const std::vector<std::string>& ArmEffectNames();

// The parameter keys an effect takes (empty for an unknown name).
std::vector<std::string> ArmEffectParameters(const std::string& name);

// Adds `effect` to a model with `dof` joints. Throws InputError naming what is wrong:
// an unknown name or key (listing the known ones), a missing or out-of-range value,
// a bad joint, or the same effect twice on one joint.
void AddArmEffect(const ArmEffect& effect, int dof, ArmEffects* effects);

// Every effect that is on, one entry per effect and joint, joints in order.
std::vector<ArmEffect> ListArmEffects(const ArmEffects& effects);

// Reads a model file's `effects:` list for the joints already read into `model`
// (joints named by their 1-based number or their name) into model->effects. Every
// problem goes into `errors` as "path:line:col: ...".
void ReadArmEffects(const YAML::Node& list, const std::string& path, ArmModel* model, ErrorList* errors);

// The friction torque (N·m or N, opposing positive qd when positive) of joint j at
// position q moving at qd: the joint's nominal viscous and Coulomb friction plus its
// friction effects (q matters only to position_friction).
// At qd = 0 it is 0 (sticking is the simulation loop's business). For a LuGre joint
// (JointEffects::presliding) it is the steady sliding torque, what the bristles settle
// to at a constant qd; ArmBristleDeflection follows them along a motion.
double ArmFrictionTorque(const ArmModel& model, int joint, double q, double qd);

// The dry friction level g(q, qd) >= 0 of joint j (N·m or N; no viscous part) at
// position q moving at speed |qd| in qd's direction (positive when qd == 0): nominal and
// effect Coulomb levels plus the position and Stribeck levels, the magnitude
// ArmFrictionTorque's dry part has.
double ArmDryFrictionLevel(const ArmModel& model, int joint, double q, double qd);

// One step of a LuGre joint's bristle deflection z over h seconds, the velocity going
// linearly from qd0 to qd1 and the rate a = sigma0 |qd0| / g(q, qd0) held over the step:
// z' = qd - a z integrated exactly, z(h) = base + slope qd1 (trapezoidal as a -> 0).
// A Maxwell-slip element has a = 0 (its slip is the simulation's clamp of the force).
// Linear in qd1, so a simulation can solve the step's end velocity and friction together;
// stable for any h.
struct ArmBristleStep {
  double base = 0;   // rad: z(h) at qd1 = 0
  double slope = 0;  // s: dz(h) / dqd1
  double At(double qd1) const { return base + slope * qd1; }
};
ArmBristleStep ArmBristleStepFrom(const ArmModel& model, int joint, double q, double z0, double qd0, double h);

// A Maxwell-slip element (JointEffects::bristle_slip) over a step that starts at
// position q and speed qd0: the dry levels it slips at either way (both >= 0; `negative` the level's size
// going negative), and, once it slips at the signed `level`, its deflection from z0 over
// h seconds, what makes sigma0 z + sigma1 (z - z0) / h equal the level. The simulation
// and the replay (ArmFrictionAlong) slip by these alike.
struct ArmSlipLevels {
  double positive = 0, negative = 0;
  double For(double force) const { return force > 0 ? positive : -negative; }  // signed, on force's side
};
ArmSlipLevels ArmMaxwellSlipLevels(const ArmModel& model, int joint, double q, double qd0);
double ArmMaxwellSlipDeflection(const JointEffects& effects, double level, double z0, double h);

// The friction torque of joint j along a logged motion (times t, positions q and
// velocities qd, one per row): ArmFrictionTorque at each row, except on a pre-sliding joint
// (JointEffects::presliding, with its Stribeck effect as a model file gives them), whose
// bristles are followed along the rows as the simulation steps them. A row is read as
// the simulation logs one, its state before a step and the command acting over that
// step: its friction is the step's to the next row (ArmBristleStepFrom; a Maxwell-slip
// element slips where its force would pass the dry level), sigma0 z + sigma1 z' at the
// step's end plus the viscous part over the step; the last row repeats the step before
// at a held velocity. The bristles start at the steady deflection of the first row's
// velocity, unloaded at rest. So the replay of a simulated log is the simulation's
// inverse on such a joint (one physics step per row), where the steady formula would
// flip the dry friction's sign at every reversal at once. Fewer than 2 rows, or times
// not matching the velocities: the steady formula.
Eigen::VectorXd ArmFrictionAlong(const ArmModel& model, int joint, const Eigen::VectorXd& t, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& qd);

// The rigid bodies the physics engines simulate: `model` with its payload lumped into
// the last link. The result has no payload effect left.
ArmModel ArmPlantModel(const ArmModel& model);

}  // namespace twinsim
