// The omni effect vocabulary of CONTRACT.md: behaviour a real robot has and the
// Newtonian model lacks. Switched on per model file (`effects:`, docs/models.md), used
// by the plants that stand in for real robots, and named by the diagnosis workflow.
//
// Every effect acts where it would on a real robot, above the physics engine, so it
// works identically on ODE, Bullet and the analytic model:
//   time_delay          commands reach the firmware `delay` s later (any delay: a command
//                       falling due within a physics step acts for the rest of that step)
//   velocity_saturation the firmware clips commands to v_max (m/s) and w_max (rad/s)
//   motor_lag           the command is followed through a first-order lag of `time_constant` s
//                       (or per axis); `braking` times as long (or short) when the set-point
//                       moves towards zero on an axis; with `field_frame: 1` the lagged
//                       velocity keeps its direction in the field while the robot turns
//                       under it (momentum), so a spinning robot's path bends against the spin;
//                       `series`: one more first-order lag before those, on every axis alike,
//                       in the robot's frame and the same both ways (a lag come on top of the
//                       robot's own response)
//   traction_limit      the wheels slip beyond a_max (m/s^2) of translational acceleration:
//                       the body follows at a_max while the wheels spin up, so the loop,
//                       reading the wheels, sees its target approached at that pace;
//                       simulated as the translational set-point changing at most a_max
//                       fast, and the floor's horizontal force capped at m * a_max
//   velocity_scale      the firmware's wheel radius is wrong: the robot moves `scale` times
//                       as fast as commanded; or per axis (`forward`, `sideways`, `turn`):
//                       each command component is scaled before the controller sees it
//   rotation_drift      the robot turns at `rate` rad per metre travelled while translating
//   turn_coupling       a translation command also turns the robot: `forward`, `sideways`
//                       rad/s of turn per m/s of forward, sideways command
//   cross_coupling      forward and sideways leak into each other: `sideways_per_forward`,
//                       `forward_per_sideways` m/s per m/s
//
// The command the firmware acts on is, in this order: the received command late by
// `time_delay`; mapped by the per-axis scales and the couplings,
//   [vx', vy', w'] = [[sx, kxy, 0], [kyx, sy, 0], [kwx, kwy, sw]] [vx, vy, w];
// clipped by velocity_saturation (so v_max and w_max are what the robot reaches);
// through motor_lag's lag in series, then its lag per axis; its translation ramped by
// traction_limit. velocity_scale's `scale` and rotation_drift act on the encoder readings.
#pragma once

#include <array>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace twinsim {

struct OmniEffects {
  double time_delay = 0;      // s; 0 = off
  double v_max = 0;           // m/s; 0 = off (velocity_saturation)
  double w_max = 0;           // rad/s; 0 = off (velocity_saturation)
  double motor_lag = 0;       // s, time constant of every axis; 0 = off
  std::array<double, 3> axis_lag{0, 0, 0};  // s, motor_lag's forward, sideways, turn where > 0 (over motor_lag)
  double lag_braking = 1;     // motor_lag's `braking`: time constants times this while slowing down; 1 = as accelerating
  bool lag_field_frame = false;  // motor_lag's `field_frame`: the lagged translation is held in the field frame
  // s, motor_lag's `series`: a first-order lag every axis's command passes through before
  // the lags above (a motor lag in series with the robot's own response); 0 = none.
  double lag_series = 0;
  double a_max = 0;           // m/s^2; 0 = off (traction_limit)
  double velocity_scale = 1;  // 1 = off (at the encoders, every axis)
  std::array<double, 3> axis_scale{1, 1, 1};  // velocity_scale's forward, sideways, turn (on the command); 1 = off
  double rotation_drift = 0;  // rad/m; 0 = off
  double turn_per_forward = 0;      // rad/s per m/s (turn_coupling `forward`); 0 = off
  double turn_per_sideways = 0;     // rad/s per m/s (turn_coupling `sideways`); 0 = off
  // rad/s per m/s (turn_coupling `third_sin`, `third_cos`): a turn of v (s sin 3φ + c cos
  // 3φ), v and φ the commanded translation's speed and direction in the robot's frame;
  // 0 = off (TurnByDirection)
  double turn_third_sin = 0;
  double turn_third_cos = 0;
  double sideways_per_forward = 0;  // m/s per m/s (cross_coupling); 0 = off
  double forward_per_sideways = 0;  // m/s per m/s (cross_coupling); 0 = off

  // The lag time constant (s) of axis 0 (forward), 1 (sideways) or 2 (turn); 0 = none.
  double LagOf(int axis) const {
    return axis_lag[static_cast<std::size_t>(axis)] > 0 ? axis_lag[static_cast<std::size_t>(axis)] : motor_lag;
  }
  bool AnyLag() const { return LagOf(0) > 0 || LagOf(1) > 0 || LagOf(2) > 0 || lag_series > 0; }
  // True when the per-axis scales or a coupling change the command.
  bool MapsCommand() const {
    return axis_scale != std::array<double, 3>{1, 1, 1} || turn_per_forward != 0 || turn_per_sideways != 0 ||
           sideways_per_forward != 0 || forward_per_sideways != 0 || turn_third_sin != 0 || turn_third_cos != 0;
  }
  // The turn (rad/s) that turn_coupling's third harmonic adds to a command of (vx, vy):
  // v sin 3φ = vy (3 vx² − vy²) / v² and v cos 3φ = vx (vx² − 3 vy²) / v², no
  // trigonometry, 0 at rest.
  double TurnByDirection(double vx, double vy) const {
    if (turn_third_sin == 0 && turn_third_cos == 0) return 0;
    const double v2 = vx * vx + vy * vy;
    if (v2 == 0) return 0;
    return (turn_third_sin * vy * (3 * vx * vx - vy * vy) + turn_third_cos * vx * (vx * vx - 3 * vy * vy)) / v2;
  }

  // Names (contract vocabulary) of the effects that are on.
  std::vector<std::string> Active() const;
  bool any() const { return !Active().empty(); }
};

// The per-axis keys of velocity_scale and motor_lag, axis 0 (forward), 1 (sideways), 2 (turn).
inline constexpr const char* kOmniAxisNames[3] = {"forward", "sideways", "turn"};

// One number of an omni effect: its key (in a model file's effect block and in
// SetOmniEffect's parameters), its valid range and the value that leaves it off. The model
// file's reader, SetOmniEffect, ListOmniEffects, OmniEffects::Active and the model writer
// all read these, so that a key, a range or a unit is written once (issue 66).
struct OmniEffectField {
  const char* key;
  double lower, upper;  // valid: lower <= v <= upper; 0 < v <= upper where `positive`
  bool positive;        // a limit: 0 is no limit, so the file gives a positive one
  double off;           // the value that leaves it off, taken where the key is not given
  bool modifier;        // shapes the effect without switching it on (motor_lag's braking)
  bool binary;          // a choice, 0 or 1 (read from a file as an integer)
  double (*get)(const OmniEffects&);
  void (*set)(OmniEffects*, double);
  // Where the diagnosis searches it when it refines the effect (diagnosis/omni_diagnosis.cc):
  // within [search_lower, search_upper], in logarithms where `search_log`. Not searched
  // (velocity_scale's per-axis keys, a modifier) where the two are equal; motor_lag's
  // per-axis keys only where a model has them (a change of an identified lag).
  double search_lower = 0, search_upper = 0;
  bool search_log = false;
};

// An effect of the vocabulary and its numbers.
struct OmniEffectSpec {
  const char* name;
  const char* unit;   // of its numbers, in the model file's comment
  const char* needs;  // where it has several switching keys and none is given: which it needs
  const char* missing_key;  // the key a model file that gives none of them is told of
  std::vector<OmniEffectField> fields;

  // True when one of its switching numbers is not off in `effects`.
  bool On(const OmniEffects& effects) const;
  // Its number called `key`; null for none.
  const OmniEffectField* Field(const std::string& key) const;
};

// The vocabulary (CONTRACT.md), in its order.
const std::vector<OmniEffectSpec>& OmniEffectSpecs();
// The effect called `name`; null for none.
const OmniEffectSpec* FindOmniEffectSpec(const std::string& name);

// The omni effect vocabulary (CONTRACT.md), in its order.
const std::vector<std::string>& OmniEffectNames();

// The parameter keys of an omni effect (model-file keys; empty for an unknown name).
std::vector<std::string> OmniEffectParameters(const std::string& name);

// Sets effect `name` with `parameters` (model-file keys, SI units) on `effects`,
// replacing its earlier values. Throws InputError for an unknown name or key (listing
// the known ones), a missing value, or a value outside the model file's range.
void SetOmniEffect(const std::string& name, const std::map<std::string, double>& parameters, OmniEffects* effects);

// The effects that are on, in the vocabulary's order, with their parameters.
std::vector<std::pair<std::string, std::map<std::string, double>>> ListOmniEffects(const OmniEffects& effects);

}  // namespace twinsim
