// The static description of a small-size (RoboCup SSL) omnidirectional robot.
//
// An OmniModel is loaded once from YAML (LoadOmniModel, documented field by field in
// docs/models.md), validated once, and never changed by a simulation step. Derived
// quantities that every backend needs (total mass and inertia, wheel geometry, the
// static load on each wheel) are computed once by Finalize() so that ODE, Bullet and
// the analytic model are built from exactly the same numbers.
//
// Wheel convention (all backends): wheel i sits at angle alpha_i around the centre, at
// distance b. Its axle points to the centre: a_i = -(cos alpha_i, sin alpha_i, 0) in the
// robot frame. A positive wheel speed is a spin about a_i; it drives the robot along
// d_i = (-sin alpha_i, cos alpha_i), so the rolling speed is
//   wheel_speed_i = (1/r) [-sin alpha_i, cos alpha_i, b] . (vx, vy, omega).
#pragma once

#include <algorithm>
#include <cmath>
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "io/yaml_overrides.h"
#include "robots/omni/omni_effects.h"
#include "robots/omni/omni_seen_inputs.h"

namespace twinsim {

// The six parameters of one on-board velocity controller (forward, sideways or
// rotation). Units are for the translational axes; the rotation axis uses rad for m
// and N·m for N.
struct PidGains {
  double kp = 0;              // N per m/s of velocity error
  double ki = 0;              // N per m of integrated error
  double kd = 0;              // N per m/s^2 of error rate
  double integral_limit = 0;  // N, the integral term is clamped to +-this (anti-windup); 0: no limit
  double output_limit = 0;    // N, the controller's output is clamped to +-this; 0: no limit
  double slew_rate = 0;       // m/s^2, the set-point follows the command at most this fast; 0: no limit

  static constexpr int kNumParameters = 6;
  // The parameters in the order above (the order PID learning uses).
  Eigen::Matrix<double, 6, 1> AsVector() const;
  static PidGains FromVector(const Eigen::Matrix<double, 6, 1>& v);
};

// The hand-tuned defaults (docs/models.md): a 60 ms velocity time constant for a
// 2.5 kg robot, an output limit under the wheels' sideways traction, 2 m/s^2 ramps.
struct OmniControllerModel {
  double rate_hz = 300;  // Hz, the micro-controller's loop rate
  PidGains forward{40, 200, 0, 4, 11, 2};      // robot x
  PidGains sideways{40, 200, 0, 4, 11, 2};     // robot y
  PidGains rotation{0.5, 3, 0, 0.3, 1.5, 30};  // yaw (N·m, rad)
};

// Driving noise (docs/models.md `driving_noise:`): the body moves at the model's velocity
// plus a slip the wheels, and so the on-board controller, do not see: a first-order
// Gauss-Markov process per robot axis with a stationary spread and a correlation time.
// The observer (estimation/omni_observer.h) estimates it and carries it into its
// predictions; identify fits it; with `simulated` the simulation loop draws it on every
// backend (sim/omni_simulation.h).
struct OmniDrivingNoise {
  std::array<double, 3> sd{0.1, 0.1, 0.5};  // forward, sideways m/s; turn rad/s: the spread standing still
  double correlation_time = 0.15;           // s
  // 1/(m/s): the spreads grow by this share per m/s of the model's translational speed
  // (a robot that wanders more the faster it drives); 0: the same at every speed.
  double per_speed = 0;
  // 1/(m/s^2): and by this share per m/s^2 of the model's translational acceleration (a
  // robot whose wheels slip when it speeds up or brakes hard).
  double per_acceleration = 0;
  // 1/(rad/s): and by this share per rad/s of the model's turn rate (wheels that slip
  // across their rollers in fast turns).
  double per_turn_rate = 0;
  bool simulated = false;                   // the simulation draws it (off: the observer's model only)
  // A slow slip beside it (docs/models.md `driving_noise.drift`): the same kind of
  // process, its own spreads (at every speed alike) and a correlation time of seconds,
  // what a run's floor, battery or worn wheel adds for a while and the response to the
  // command does not hold (a run's own drift). The observer learns it over the frames and
  // carries it into its predictions; identify fits it on the predictions a second ahead.
  struct Drift {
    std::array<double, 3> sd{0, 0, 0};  // forward, sideways m/s; turn rad/s; all 0: none
    double correlation_time = 5;       // s
    bool any() const { return sd[0] > 0 || sd[1] > 0 || sd[2] > 0; }
  };
  Drift drift;

  // The spread (m/s or rad/s) of axis a (forward, sideways, turn) at `speed` (m/s),
  // `acceleration` (m/s^2) and `turn_rate` (rad/s, either sign).
  double Spread(int a, double speed, double acceleration, double turn_rate) const {
    return sd[static_cast<std::size_t>(a)] * Growth(speed, acceleration, turn_rate);
  }
  // The spreads' factor over standing still there.
  double Growth(double speed, double acceleration, double turn_rate) const {
    return 1 + per_speed * speed + per_acceleration * acceleration + per_turn_rate * std::abs(turn_rate);
  }
};

// The state observer's noise model (estimation/omni_observer.h; docs/models.md
// `observer:`): what the model does not predict, as its Kalman filter sees it.
struct OmniObserverModel {
  // The square root of the spectral density of the white acceleration that moves the
  // model's own velocity beyond what it predicts (errors of the model), per robot axis:
  // forward and sideways in m/s per sqrt(s), turn in rad/s per sqrt(s).
  std::array<double, 3> process_noise{0.1, 0.1, 1.0};
  // Standard deviation of a camera pose: x and y (m), theta (rad); 0 = the vision block's
  // noise, at least kMinMeasurementNoiseXy / kMinMeasurementNoiseTheta.
  double measurement_noise_xy = 0;
  double measurement_noise_theta = 0;

  static constexpr double kMinMeasurementNoiseXy = 5e-4;     // m
  static constexpr double kMinMeasurementNoiseTheta = 5e-3;  // rad

  // The intervals' safeguard (identify's conformal scale; docs/identification.md, "The
  // intervals' safeguard"): k frames ahead, the predicted covariance of the position is
  // multiplied by position^2 and that of the heading by heading^2 (their cross terms by
  // the product), so the measured pose lands in the 90 % regions as often as on the
  // held-out rows identify scaled them on. Horizons strictly increasing; between two the
  // scales are interpolated in log(k), before the first and after the last held. Empty:
  // the filter's covariance as it is.
  // Out of the fit's reach (docs/identification.md, "Intervals out of the fit's reach"):
  // each scale grows by its `growth` times the prediction's mean distance from the seen
  // inputs (below) along its k frames, s (1 + g d); the growths are interpolated
  // linearly in log(k).
  struct IntervalScale {
    int frames = 0;
    double position = 1, heading = 1;
    double position_growth = 0, heading_growth = 0;  // per unit of distance; 0: none
  };
  std::vector<IntervalScale> interval_scale;
  // The scales (position, heading) k frames ahead, `distance` from the seen inputs.
  std::array<double, 2> IntervalScaleAt(int k, double distance = 0) const;
  static constexpr double kMaxIntervalScale = 20;  // either way: 1/20 to 20
  static constexpr double kMaxIntervalGrowth = 1000;
  // The inputs identify's fit saw, which a growth measures distances from; empty when
  // no scale grows.
  OmniSeenInputs seen_inputs;
  // The covariance of the response's parameters identify estimated (docs/identification.md,
  // "The parameters' own uncertainty"): `parameters` by identify's names and in its units
  // (delay in s, forward.gain, forward.lag in s, turn_coupling.forward, ...), `matrix` their
  // covariance, symmetric with positive diagonal. The replay's predictions add the spread
  // the parameters make (OmniReplayOptions::parameter_shifts). Empty: none.
  struct ParameterCovariance {
    std::vector<std::string> parameters;
    Eigen::MatrixXd matrix;
    bool empty() const { return parameters.empty(); }
  };
  ParameterCovariance parameter_covariance;
  static constexpr int kMaxCovarianceParameters = 64;
};

struct OmniModel {
  std::string name;
  std::string source_path;  // file it was loaded from ("" when built in code)
  // The engine (analytic, ode, bullet) the model's response was fitted on by identify or
  // diagnose; "" for a model from a data sheet. The engines part where wheels near their
  // grip, so replay, diagnose and batch replays use this one unless told otherwise
  // (ReplayEngineFor, below), and say so when told.
  std::string fitted_on;

  // Chassis (everything but the wheels).
  double chassis_mass = 2.3;        // kg
  double chassis_radius = 0.089;    // m
  double chassis_height = 0.14;     // m
  double chassis_inertia_z = 0;     // kg m^2 about the vertical axis; 0 = solid cylinder
  double com_height = 0.045;        // m above the floor
  // m, the chassis' centre of mass in the floor plane, robot frame, from the centre the
  // wheels are placed around (a battery off to one side); (0, 0) = centred.
  Eigen::Vector2d chassis_com = Eigen::Vector2d::Zero();
  double ground_clearance = 0.008;  // m between the floor and the chassis' underside
  // The flat front the kicker and dribbler sit in: the chassis cylinder cut by a vertical
  // plane this far ahead of the centre (robot +x). 0 = kDefaultFrontRatio x radius. Only
  // the ball sees it (docs/ball.md); walls and other robots meet the full cylinder.
  double front_distance = 0;        // m

  // The kicker and dribbler in the flat front (docs/ball.md).
  double kicker_max_speed = 6.5;    // m/s, faster kicks are clipped (the league's limit)
  double dribbler_max_force = 1.0;  // N, the most the dribbler pulls the ball towards the front with
  // rpm at which the dribbler pulls with all of dribbler_max_force; slower, the most it
  // pulls with scales with the speed. 0: any speed above 0 pulls with all of it.
  double dribbler_full_speed = 0;

  // Wheels (all alike).
  std::vector<double> wheel_angles;  // rad, alpha_i of each wheel around the centre
  double wheel_distance = 0.081;     // m, b: centre to wheel contact, in the floor plane
  double wheel_radius = 0.027;       // m
  double wheel_width = 0.012;        // m
  double wheel_mass = 0.05;          // kg per wheel
  double wheel_friction = 0.8;       // Coulomb coefficient along the rolling direction
  double roller_friction = 0.02;     // Coulomb coefficient across the wheel (rollers)
  double bearing_damping = 2e-5;     // N·m per rad/s on each wheel's spin

  // Motors, seen at the wheel (gear included).
  double motor_stall_torque = 0.5;  // N·m at zero speed
  double motor_no_load_speed = 160;  // rad/s where the available torque reaches zero
  double encoder_counts_per_rev = 0;  // counts per wheel turn; 0 = ideal encoder
  // Per wheel, the share of the stall torque its motor gives (a worn motor, a weak
  // driver); empty = all 1.
  std::vector<double> motor_strength;

  OmniControllerModel controller;

  // The delay loop, in camera frames (the scene sets the frame rate).
  int command_delay_frames = 2;  // frames from sending a command to the robot acting on it
  int vision_delay_frames = 2;   // frames from the camera's exposure to the observer

  // What a real robot does that the Newtonian model does not (omni_effects.h).
  OmniEffects effects;

  // What the robot does beyond its model: driving noise (see OmniDrivingNoise).
  OmniDrivingNoise driving_noise;
  // How the observer weighs the model against the camera (estimation/omni_observer.h).
  OmniObserverModel observer;

  // Vision (the observation model).
  double vision_noise_xy = 0.0;      // m, standard deviation of x and y
  double vision_noise_theta = 0.0;   // rad, standard deviation of theta
  double vision_drop_probability = 0;  // probability that a frame is lost
  double vision_repeat_probability = 0;  // probability that the camera repeats its last pose (no new measurement)
  double vision_time_jitter = 0;       // s, each frame's time stamp is off by up to this (uniform)

  // ---- Derived by Finalize() ----
  double total_mass = 0;          // kg, chassis and wheels
  double total_inertia_z = 0;     // kg m^2 about the vertical axis through the centre
  Eigen::Vector2d com_offset = Eigen::Vector2d::Zero();  // m, whole robot's centre of mass (robot frame)
  double wheel_spin_inertia = 0;  // kg m^2, one wheel about its axle
  double wheel_inertia_diametral = 0;  // kg m^2, one wheel about a diameter
  Eigen::MatrixXd geometry;       // n x 3, rows [-sin a_i, cos a_i, b] (m for the last)
  Eigen::VectorXd wheel_load;     // n, N, static normal force on each wheel

  // The observer's camera noise (m, rad): observer.measurement_noise_*, else the vision
  // block's, never below the minimum.
  double ObserverNoiseXy() const;
  double ObserverNoiseTheta() const;

  // s, from sending a command to the camera's pose showing its effect at `frame_period`:
  // the command and vision frames and the time_delay effect.
  double TotalDelaySeconds(double frame_period) const {
    return (command_delay_frames + vision_delay_frames) * frame_period + effects.time_delay;
  }

  int num_wheels() const { return static_cast<int>(wheel_angles.size()); }
  // m, the flat front's distance from the centre (front_distance, or its default).
  double FrontDistance() const { return front_distance > 0 ? front_distance : kDefaultFrontRatio * chassis_radius; }
  static constexpr double kDefaultFrontRatio = 0.82;  // a league robot's: 73 mm of a 89 mm radius
  // m, half the flat front's width, where it meets the chassis circle: sqrt(r^2 - d^2)
  // (0 for a front at or beyond the radius, which a model file cannot give).
  double FrontHalfWidth() const {
    const double d = FrontDistance();
    return std::sqrt(std::max(0.0, chassis_radius * chassis_radius - d * d));
  }
  // The strength of wheel i's motor (1 unless motor_strength says otherwise).
  double MotorStrength(int wheel) const {
    return motor_strength.empty() ? 1.0 : motor_strength[static_cast<std::size_t>(wheel)];
  }
  // Fills the derived fields; call after changing any parameter.
  void Finalize();
  // The 3 x 3 rigid-body mass matrix about the robot's centre for (vx, vy, omega):
  // [[m, 0, -m yc], [0, m, m xc], [-m yc, m xc, Iz]] (chassis and wheels, no spin).
  Eigen::Matrix3d RigidBodyMass() const;
  // Returns an empty string when the model is physically consistent, else every problem.
  std::string Validate() const;
};

// True where two wheel angles (rad) put the wheels on one spot (within 1 mrad, any turn
// apart): OmniModel::Validate's test, and the model file reader's with its line.
bool SameWheelAngle(double a, double b);

// Loads and validates an omni model; throws InputError with "path:line:col: ..." lines.
OmniModel LoadOmniModel(const std::string& path);
// As LoadOmniModel, with `overrides` laid over the file's keys (io/yaml_overrides.h)
// before it is read: a variant with the file's checks. Throws InputError as above.
OmniModel LoadOmniModel(const std::string& path, const YamlOverrides& overrides);
// As LoadOmniModel, from YAML text; `name` stands for the file in messages.
OmniModel LoadOmniModelFromString(const std::string& yaml, const std::string& name);

// The scales (position, heading) of a safeguard's list k frames ahead, `distance` from
// the seen inputs: OmniObserverModel::IntervalScaleAt's rule, for any holder of such a
// list (a model's observer, a learned predictor); {1, 1} for an empty list.
std::array<double, 2> IntervalScaleAt(const std::vector<OmniObserverModel::IntervalScale>& scales, int k,
                                      double distance = 0);

class YamlMap;
// Reads the list under `key` of `parent` (a model file's observer.interval_scale, a
// predictor file's interval_scale): {frames, position, heading}, with position_growth
// and heading_growth where `growth` allows them, the horizons increasing; each problem
// into the parent's errors.
void ReadIntervalScales(YamlMap& parent, const std::string& key, bool growth,
                        std::vector<OmniObserverModel::IntervalScale>* out);

// The engine a command replays `model` on: `asked` (its --backend) where given, else the
// engine the model was fitted on, else `fallback` (the command's own default). Where
// `asked` is a physics engine other than the one the model was fitted on, *note (if
// given) receives one sentence saying so; else it is cleared.
std::string ReplayEngineFor(const OmniModel& model, const std::string& asked, const std::string& fallback,
                            std::string* note = nullptr);

inline constexpr double kGravity = 9.81;  // m/s^2

}  // namespace twinsim
