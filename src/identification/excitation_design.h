// Optimised excitation: the Fourier coefficients (fourier_trajectory.h) that make an
// arm's base parameters best determined by the torques measured along one period
// (Swevers et al. 1997; seed 001, section IV-A).
//
// The criterion is the condition number of the stacked base regressor
//
//   W = [ Y_b(q(t_1), qd(t_1), qdd(t_1)) ; ... ; Y_b(q(t_M), ...) ] S^-1     (M n x r)
//
// over M samples of one period, friction columns included (Y_b = BaseParameters::Reduce
// of the arm's Regressor). S = diag(s_j) scales every column by its typical size, the
// RMS of that column over states drawn uniformly within the design limits (positions,
// velocities, accelerations): the condition number then compares parameters in units
// of "torque they typically cause", which neither depends on the units of the parameters
// nor rewards an excitation that just moves less (docs/excitation.md).
//
// Constraints, at every sample: each joint inside its position limits less a margin,
// |qd| within the model's velocity_limit, |qdd| within an acceleration limit (options),
// and the nominal model's inverse-dynamics torque within a fraction of effort_limit.
// They enter as smooth quadratic penalties whose weight grows over a few rounds;
// ceres::GradientProblemSolver (LBFGS) minimises log(cond W) + penalties with an
// analytic gradient: d log(cond)/dW from the extreme eigenvectors of W'W, chained
// through the regressor by central differences in (q, qd, qdd) and through the Fourier
// basis exactly. Several seeded random feasible starts run (on `threads` threads, each
// start independent, so the result does not depend on the thread count); the best final
// trajectory that passes a dense check of every limit at the model's sample time wins.
// A final trajectory that still touches a limit is shrunk about q0 until it passes.
//
//   ExcitationOptions options;           // 5 harmonics of 0.1 Hz, 8 starts
//   ExcitationSummary summary;
//   FourierTrajectory traj = DesignExcitation(model, options, &summary);
//   std::puts(summary.FullReport().c_str());
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "identification/fourier_trajectory.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

inline constexpr double kDefaultAccelerationLimit = 20.0;  // rad/s^2 or m/s^2

struct ExcitationOptions {
  int harmonics = 5;                 // N
  double fundamental = 0.1;          // Hz; the period is 1/fundamental
  int samples_per_period = 200;      // M, regressor samples in the criterion
  bool start_at_rest = true;         // qd(0) = qdd(0) = 0: trials can start from standstill
  double position_margin = 0.05;     // rad or m kept from each position limit
  std::vector<double> acceleration_limits;  // rad/s^2 or m/s^2 per joint; empty: kDefaultAccelerationLimit each
  double torque_fraction = 0.9;      // nominal torque within this fraction of effort_limit; 0: not constrained
  int starts = 8;                    // random feasible starting points
  int max_iterations = 100;          // LBFGS iterations per penalty round
  int penalty_rounds = 4;            // penalty weights 10, 100, 1000, ...
  double coulomb_smoothing = 0.05;   // rad/s or m/s: tanh(qd / this) stands for sign(qd) in the criterion
  double check_sample_time = 0;      // s, dense limit check; 0: the model's sample_time
  std::uint64_t seed = 1;
  int threads = 2;

  // True when usable; otherwise false with the first problem in *why.
  bool IsValid(std::string* why) const;
};

// The limits a design must respect, per joint (infinity where there is none).
struct ExcitationLimits {
  Eigen::VectorXd lower, upper;   // rad or m, the model's limits less the margin (+-pi where unlimited)
  Eigen::VectorXd velocity;       // rad/s or m/s
  Eigen::VectorXd acceleration;   // rad/s^2 or m/s^2
  Eigen::VectorXd torque;         // N·m or N: torque_fraction * effort_limit
};

// How close a trajectory comes to each limit (one entry per joint).
struct ExcitationJointMargins {
  double q_min = 0, q_max = 0;                  // rad or m, the range covered
  double lower = 0, upper = 0;                  // rad or m, the design's position limits
  double velocity_peak = 0, velocity_limit = 0;            // rad/s or m/s
  double acceleration_peak = 0, acceleration_limit = 0;    // rad/s^2 or m/s^2
  double torque_peak = 0, torque_limit = 0;                // N·m or N, nominal model
  // rad or m: the closest approach to the design's position limits (negative: outside).
  double position_margin() const { return std::min(q_min - lower, upper - q_max); }
  // True when every peak is within its limit and the range within the position limits.
  bool feasible() const;
};

struct ExcitationStart {
  double initial_condition = 0;  // criterion of the random feasible start
  double final_condition = 0;    // after optimisation (and shrinking, if needed)
  int iterations = 0;            // LBFGS iterations over all penalty rounds
  double shrink = 1;             // factor the oscillation was scaled by to pass the dense check
  bool feasible = false;
};

struct ExcitationSummary {
  std::string model;
  int harmonics = 0;
  double fundamental = 0;             // Hz
  int parameters = 0;                 // base parameters (columns of W)
  int best_start = -1;
  double start_condition = 0;         // the winning start's random feasible trajectory
  double final_condition = 0;         // the design (scaled columns, the criterion)
  double random_condition_median = 0; // median over all random feasible starts
  double final_condition_unscaled = 0;     // W without S: raw SI units
  double final_condition_equilibrated = 0; // W with unit-norm columns
  std::vector<ExcitationStart> starts;
  std::vector<ExcitationJointMargins> margins;
  int iterations = 0;                 // over all starts
  double seconds = 0;                 // wall time

  // "condition number 41.3 -> 6.02 (random feasible median 37.5), 8 starts, 1290 iterations, 9.8 s"
  std::string BriefReport() const;
  // Per start and per joint: conditions, iterations, limits and margins.
  std::string FullReport() const;
};

// The design limits for `model` under `options`. Throws InputError when
// acceleration_limits has not one entry per joint, or the margin leaves no room.
ExcitationLimits ResolveExcitationLimits(const ArmModel& model, const ExcitationOptions& options);

// S: each base column's RMS over 2000 states uniform within the limits (velocity +-2
// where unlimited). Deterministic (a fixed internal seed).
Eigen::VectorXd ExcitationColumnScales(const ArmModel& model, const BaseParameters& base,
                                       const ExcitationLimits& limits);

// The stacked base regressor over `samples` instants of one period (samples n x r,
// exact sign(qd) in the Coulomb columns, unscaled).
Eigen::MatrixXd StackedBaseRegressor(const ArmModel& model, const BaseParameters& base,
                                     const FourierTrajectory& trajectory, int samples);

// cond(W S^-1) for column scales `scales` (r); all ones gives the unscaled number.
double ExcitationCondition(const ArmModel& model, const BaseParameters& base, const Eigen::VectorXd& scales,
                           const FourierTrajectory& trajectory, int samples);

// Peaks of q, qd, qdd and the nominal torque at every multiple of `sample_time` over one
// period, against `limits`.
std::vector<ExcitationJointMargins> CheckExcitationLimits(const ArmModel& model, const FourierTrajectory& trajectory,
                                                          const ExcitationLimits& limits, double sample_time);

// A random trajectory inside the limits: coefficients uniform with amplitudes falling as
// 1/l, q0 near the middle of the range, then scaled to a random 50..90 % of the largest
// feasible size. What the optimiser starts from, and the baseline it is compared with.
FourierTrajectory RandomFeasibleExcitation(const ArmModel& model, const ExcitationOptions& options,
                                           std::uint64_t seed);

// The optimiser's objective for one trajectory (all coefficients free):
// log(cond(W S^-1)) + penalty_weight * (sum of squared normalised limit excesses, the
// limits tightened by 1 %), and where `gradient` is given its analytic derivative with
// respect to q0, a and b in the same shapes. NaN when W is rank deficient. Throws
// InputError for invalid options or a trajectory of other shape than the options'.
double EvaluateExcitationObjective(const ArmModel& model, const ExcitationOptions& options,
                                  const FourierTrajectory& trajectory, double penalty_weight,
                                  FourierTrajectory* gradient = nullptr);

// Called after each finished start: (starts done, starts in all, best condition so far).
using ExcitationProgress = std::function<void(int, int, double)>;

// Designs the excitation. Throws InputError for invalid options or a model whose limits
// leave no room; CheckFailed when no start ends inside the limits.
FourierTrajectory DesignExcitation(const ArmModel& model, const ExcitationOptions& options,
                                   ExcitationSummary* summary = nullptr, const ExcitationProgress& progress = {});

}  // namespace twinsim
